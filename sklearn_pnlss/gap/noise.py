"""Noise floor of the measurements and the test of whether a gap is real.

The noise is what changes from one period to the next of a steady-state
periodic measurement; its spectrum gives both the floor that no model can
go below and the effective number of independent samples, which the test of
a gap against that floor needs (band-limited noise has far fewer than one
per sample).
"""
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..frequency.noise import periodic_noise_variance

__all__ = ["NoiseFloor", "drift_free_variance", "estimate_noise", "gap_test"]


@dataclass
class NoiseFloor:
    """Output noise estimated from the periods of the training signals.

    Attributes
    ----------
    variance : float
        Noise variance per sample, m^2.
    spectrum : ndarray of shape (period // 2 + 1,)
        Noise variance of one period's unitary DFT per bin, m^2.
    dof_per_sample : float
        Independent real samples per time sample (1 for white noise, about
        the occupied fraction of the band otherwise).
    """

    variance: float
    spectrum: np.ndarray
    dof_per_sample: float

    @property
    def rms(self):
        return float(np.sqrt(self.variance))


def drift_free_variance(y_list, period):
    """Noise variance of one period's unitary DFT per bin, from what changes
    between periods once a slow trend over the periods is removed.

    A structure that drifts (stiffness changing with temperature) changes
    its response from period to period too; taken as noise, that change
    would raise the floor up to the gap itself and hide it.  So each bin is
    regressed on a polynomial in the period index, of degree two with four
    periods or more, one with three, and the residual spread is the noise
    (``P - 3``, ``P - 2`` degrees of freedom); two periods give their plain
    spread (one).  A strong drift is not a polynomial of the period index
    (near a resonance the response is far from linear in the stiffness), so
    the result is then an upper bound.  None without a signal of two
    periods.
    """
    var = periodic_noise_variance([np.asarray(y, dtype=float).reshape(-1, 1) for y in y_list], period,
                                  trend_degree=2)
    return None if var is None else var[:, 0]


def estimate_noise(y_list, period):
    """:class:`NoiseFloor` from signals of two periods or more (None if none)."""
    if period is None:
        return None
    s = drift_free_variance(y_list, period)
    if s is None:
        return None
    # Two-sided spectrum: the bins between DC and Nyquist count twice.
    weights = np.full(s.size, 2.0)
    weights[0] = 1.0
    if period % 2 == 0:
        weights[-1] = 1.0
    total = np.sum(weights * s)
    variance = total / period
    # Satterthwaite: a sum of independent variance terms has the degrees of
    # freedom of (sum s)^2 / sum s^2, each complex bin carrying two.
    dof = total**2 / np.sum(weights * s**2) if total > 0 else period
    return NoiseFloor(float(variance), s, float(min(dof / period, 1.0)))


def gap_test(mse, noise, n_samples):
    """P-value of the hypothesis that an error of mean square ``mse`` over
    ``n_samples`` samples is noise alone.

    The scaled mean square of Gaussian noise with ``nu`` effective degrees
    of freedom is chi-square(nu) / nu.
    """
    nu = max(noise.dof_per_sample * n_samples, 1.0)
    return float(stats.chi2.sf(mse / noise.variance * nu, nu))
