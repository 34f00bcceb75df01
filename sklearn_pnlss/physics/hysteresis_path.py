"""A Bouc-Wen element's force along a prescribed periodic displacement.

The gap locator reads every force law off the measured relative motion of a
connection; a hysteretic law's force depends on that motion's history,
not on its present value, so it is integrated along the record.  With
``nu = 1`` the state's rate per unit of displacement is linear in ``z`` on
either side of ``z = 0``,

.. math:: \\frac{dz}{dx} = \\alpha - \\beta\\,(\\gamma\\,s\\,z + \\delta\\,|z|),
          \\qquad s = \\mathrm{sign}(\\dot x),

so each sample's step is solved exactly (an exponential in the
displacement travelled), not by a time-stepping rule: the force is the
element's at any sample rate.  The record is run twice and the second pass
kept: the periodic steady state, whose memory of the start has decayed
over a whole record of motion.
"""
import numpy as np
from numba import njit

__all__ = ["bouc_wen_along"]

#: Passes over the periodic record: the last one is returned.
PASSES = 2


@njit(cache=True)
def _travel(z, length, alpha, k):
    """``z`` after a displacement ``length`` along ``dz/dl = alpha - k z``:
    exact, or linear where ``k`` hardly acts over the step (the
    exponential would round off)."""
    if abs(k) * length < 1e-12:
        return z + (alpha - k * z) * length
    return alpha / k + (z - alpha / k) * np.exp(-k * length)


@njit(cache=True)
def _advance(z, length, alpha, rate_pos, rate_neg):
    """``z`` after a displacement ``length`` (> 0) travelled in the
    direction where ``z`` counts positive: ``dz/dl = alpha - k z`` with
    ``k = rate_pos`` for ``z >= 0`` and ``rate_neg`` below."""
    if z < 0.0:
        # below zero first; the rate at z = 0 is alpha, so z rises through it
        k = rate_neg
        if abs(k) * length < 1e-12:
            reach = -z / alpha
        elif alpha - k * z <= 0.0:  # a loop that falls away below zero never comes back
            reach = np.inf
        else:
            reach = np.log((alpha - k * z) / alpha) / k
        if reach >= length:
            return _travel(z, length, alpha, k)
        length -= reach
        z = 0.0
    return _travel(z, length, alpha, rate_pos)


@njit(cache=True)
def _path(d, alpha, beta, gamma, delta, out):
    n = d.size
    z = 0.0
    for _ in range(PASSES):
        for i in range(n):
            step = d[i] - d[i - 1]  # d[-1]: the record is periodic
            if step > 0.0:
                z = _advance(z, step, alpha, beta * (gamma + delta), beta * (gamma - delta))
            elif step < 0.0:
                # by symmetry: -z in the mirrored direction
                z = -_advance(-z, -step, alpha, beta * (gamma + delta), beta * (gamma - delta))
            out[i] = z
    return out


def bouc_wen_along(displacement, alpha, beta, gamma, delta):
    """The periodic steady-state force ``z`` of a Bouc-Wen element with
    ``nu = 1`` (see :class:`~sklearn_pnlss.physics.BoucWen`) along one period
    of a displacement.

    Parameters
    ----------
    displacement : array-like of shape (n_samples,)
        One period of the displacement, m, sampled finely enough that it is
        monotone between samples.
    alpha, beta, gamma, delta : float
        The element's parameters (``nu = 1``; ``alpha > 0``, ``beta >= 0``).

    Returns
    -------
    force : ndarray of shape (n_samples,)

    Examples
    --------
    A Jenkins-like element (``gamma = delta = 1/2``) saturates at
    ``alpha / beta`` once the motion exceeds a few slip displacements
    ``1 / beta``:

    >>> import numpy as np
    >>> from sklearn_pnlss.physics.hysteresis_path import bouc_wen_along
    >>> x = 1e-3 * np.sin(2 * np.pi * np.arange(1000) / 1000)
    >>> z = bouc_wen_along(x, alpha=1e5, beta=1e4, gamma=0.5, delta=0.5)
    >>> round(float(z.max()), 2)
    10.0
    """
    d = np.ascontiguousarray(displacement, dtype=np.float64)
    if d.ndim != 1 or d.size < 2:
        raise ValueError(f"displacement must be one period, a 1-D array of two samples or more; got shape {d.shape}.")
    if not alpha > 0 or not beta >= 0:
        raise ValueError(f"alpha must be > 0 and beta >= 0 (a loop that starts along a positive stiffness); "
                         f"got alpha={alpha!r}, beta={beta!r}.")
    return _path(d, float(alpha), float(beta), float(gamma), float(delta), np.empty_like(d))
