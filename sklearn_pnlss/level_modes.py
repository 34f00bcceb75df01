"""How a structure's modes move with the excitation level, in the data and
in a fitted model.

A nonlinear structure tested at several levels has, at each level, a best
linear approximation whose modes soften (or stiffen) and damp more (or
less) as the amplitude grows: friction and clearances in joints make the
frequencies fall and the damping rise. :func:`modes_by_level` fits a linear
model to each level's measurement and, given a fitted nonlinear model, to
that model's simulation of the same input, and pairs the modes: what a
vibration engineer reads as the model's amplitude dependence against the
structure's. On lightly damped modes the simulation error of a level
between fitted ones lies mostly at the modes whose frequency or damping the
model misses there, by a fraction of their half-power bandwidth.
"""
from dataclasses import dataclass

import numpy as np

from .estimators import BLAEstimator
from .statespace.linear import modal_parameters

__all__ = ["LevelModes", "modes_by_level"]


@dataclass
class LevelModes:
    """Modes of a linear model of each level; ``str()`` gives the table
    (levels numbered from 1 in the order given).

    Attributes
    ----------
    input_rms : ndarray of shape (n_levels,)
        Rms of each level's input (all inputs together).
    frequencies, damping : ndarray of shape (n_levels, n_modes)
        Natural frequency (Hz, or cycles per sample without ``fs``) and
        damping ratio of each mode of the measurement's linear model at each
        level; mode ``k`` is the one paired with mode ``k`` of the first
        level (NaN where a level has no partner).
    model_frequencies, model_damping : ndarray of shape (n_levels, n_modes) or None
        The same of the linear model of the fitted model's simulation, each
        mode paired with the measurement's nearest one in frequency at that
        level; None without a model.
    """

    input_rms: np.ndarray
    frequencies: np.ndarray
    damping: np.ndarray
    model_frequencies: np.ndarray | None = None
    model_damping: np.ndarray | None = None

    def to_dict(self):
        """Plain Python values (JSON-ready); NaN becomes None."""
        def plain(a):
            return None if a is None else [[None if np.isnan(v) else float(v) for v in row] for row in a]

        return {"input_rms": [float(v) for v in self.input_rms], "frequencies": plain(self.frequencies),
                "damping": plain(self.damping), "model_frequencies": plain(self.model_frequencies),
                "model_damping": plain(self.model_damping)}

    def __str__(self):
        lines = []
        for i, rms in enumerate(self.input_rms):
            cells = []
            for k in range(self.frequencies.shape[1]):
                cell = f"{self.frequencies[i, k]:7.3f} {100 * self.damping[i, k]:5.2f} %"
                if self.model_frequencies is not None:
                    cell += f" (model {self.model_frequencies[i, k]:7.3f} {100 * self.model_damping[i, k]:5.2f} %)"
                cells.append(cell)
            lines.append(f"level {i + 1} (input rms {rms:.4g}): " + "  ".join(cells))
        return "\n".join(lines)

    __repr__ = __str__


def _oscillating_modes(A, fs):
    """Frequencies and damping ratios of the complex pole pairs of ``A``
    (real poles are no modes), by frequency."""
    freq, damp = modal_parameters(A, 1.0 if fs is None else fs)
    keep = damp < 1.0 - 1e-9
    return freq[keep], damp[keep]


def _paired(freq, damp, ref):
    """``freq, damp`` reordered to the reference frequencies ``ref``: each
    mode belongs to the reference mode nearest to it (relative distance),
    and each reference mode takes the nearest of its own; NaN where none
    is. A mode the other model lacks so stays unpaired instead of taking a
    neighbour's partner (a pairing that minimises the total distance would
    shift a whole row of modes by one)."""
    out_f, out_d = np.full(ref.size, np.nan), np.full(ref.size, np.nan)
    if ref.size == 0 or freq.size == 0:
        return out_f, out_d
    distance = np.abs(np.log(freq[:, None] / ref[None, :]))  # (modes, reference modes)
    owner = np.argmin(distance, axis=1)
    for k in range(ref.size):
        mine = np.flatnonzero(owner == k)
        if mine.size:
            best = mine[np.argmin(distance[mine, k])]
            out_f[k], out_d[k] = freq[best], damp[best]
    return out_f, out_d


def modes_by_level(X_levels, y_levels, estimator=None, *, n_states, period, fs=None):
    """The modes of a linear model of each excitation level, of the
    measurement and of a fitted model's simulation.

    Each level's measurement, and the fitted ``estimator``'s simulation of
    the same input, get a :class:`~sklearn_pnlss.BLAEstimator` of
    ``n_states`` (the best linear approximation on the excited lines and a
    state-space model of it); their modes are paired across levels and
    between measurement and model by frequency.

    Parameters
    ----------
    X_levels, y_levels : list of array-like
        The input and output signals of each level, as
        :meth:`~sklearn_pnlss.BLAEstimator.fit` takes them (periodic,
        whole periods), ordered by level.
    estimator : fitted estimator or None, default=None
        A model with ``predict``; None: the measurement's modes only.
    n_states : int
        Order of each level's linear model.
    period : int
        Samples per period of the excitation.
    fs : float or None, default=None
        Sampling frequency in Hz; None: frequencies in cycles per sample.

    Returns
    -------
    LevelModes

    Examples
    --------
    The Bouc-Wen oscillator's hysteresis dissipates more, and its linear
    model's mode moves up, as the force grows:

    >>> import numpy as np
    >>> from sklearn_pnlss.datasets import simulate_bouc_wen
    >>> from sklearn_pnlss.level_modes import modes_by_level
    >>> from sklearn_pnlss.signals import multisine
    >>> u, _ = multisine(2048, fs=750.0, f_band=(5.0, 150.0), random_state=0)
    >>> X = [np.tile(rms * u[0], (2, 1)) for rms in (5.0, 50.0)]  # two periods each
    >>> y = [np.tile(simulate_bouc_wen(x[:2048, 0], periodic=True)[:, None], (2, 1)) for x in X]
    >>> modes = modes_by_level(X, y, n_states=2, period=2048, fs=750.0)
    >>> np.round(modes.frequencies[:, 0], 1), np.round(100 * modes.damping[:, 0], 1)
    (array([36.5, 40.2]), array([3.1, 9.4]))
    """
    if len(X_levels) != len(y_levels) or not len(X_levels):
        raise ValueError(
            f"X_levels and y_levels must be lists of the same, non-zero length (one signal per level); "
            f"got {len(X_levels)} and {len(y_levels)}."
        )
    rms, data, model = [], [], []
    for X, y in zip(X_levels, y_levels):
        X = np.asarray(X, dtype=float)
        rms.append(float(np.sqrt(np.mean(X**2))))
        linear = BLAEstimator(n_states, period=period, fs=fs).fit(X, y)
        data.append(_oscillating_modes(linear.A_, fs))
        if estimator is not None:
            simulated = BLAEstimator(n_states, period=period, fs=fs).fit(X, estimator.predict(X))
            model.append(_oscillating_modes(simulated.A_, fs))
    ref = data[0][0]
    freq, damp = map(np.array, zip(*(_paired(f, d, ref) for f, d in data)))
    out = LevelModes(np.array(rms), freq, damp)
    if estimator is not None:
        # each level's model modes against that level's measured ones, which
        # have moved from the first level's
        paired = [_paired(f, d, np.where(np.isnan(measured), ref, measured)) for (f, d), measured in zip(model, freq)]
        out.model_frequencies, out.model_damping = map(np.array, zip(*paired))
    return out
