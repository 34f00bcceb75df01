"""Starting points of the linear candidates (second mode, recalibration)
from the measured change of dynamic stiffness.

A lightly damped second mode makes the simulation error a rugged function
of its frequency: a local optimiser started a factor two off settles on a
wrong resonance.  Linear candidates, however, change the structure's
dynamic stiffness ``1 / G(w)`` by a known function of their parameters, and
the measured change is there to read: the dynamic stiffness of the
measurement's BLA minus that of the nominal simulation's BLA on the same
inputs (which holds the nominal's own nonlinear forces as they act at the
measured levels).  Fitting that difference line by line is cheap and
global (a dense grid over the resonance frequency), and gives the
simulation-error fit a start in the right basin.
"""
from dataclasses import dataclass

import numpy as np

from ...frequency.bla import periodic_bla
from ...utils.validation import is_periodic
from .effect import recalibration_unit
from .trial_columns import TrialColumns

__all__ = ["StiffnessChange", "measured_stiffness_change", "second_mode_start", "second_mode_joint_start",
           "recalibration_start"]


@dataclass
class StiffnessChange:
    """Measured change of the dynamic stiffness at the excited lines.

    Attributes
    ----------
    omega : ndarray of shape (K,)
        Angular frequencies of the excited lines, rad/s.
    delta : ndarray of shape (K,), complex
        ``1 / G_measured - 1 / G_nominal``, N/m.
    weight : ndarray of shape (K,)
        Least-squares weights that turn a stiffness misfit into output
        error: ``|G_measured G_nominal U|^2`` (output error is about
        ``G_m G_n dK U``).
    """

    omega: np.ndarray
    delta: np.ndarray
    weight: np.ndarray


def measured_stiffness_change(u_list, y_list, y_nominal, period, fs):
    """:class:`StiffnessChange` from the periodic training signals, or None
    without at least one steady-state periodic signal."""
    picks = [i for i, u in enumerate(u_list) if is_periodic(u.size, period)]
    if not picks:
        return None

    def split(signals):
        return [signals[i].reshape(-1, period, 1) for i in picks]

    try:
        measured = periodic_bla(split(u_list), split(y_list))
        nominal = periodic_bla(split(u_list), split(y_nominal), lines=measured.lines)
    except ValueError:
        return None
    g_m, g_n = measured.frf[:, 0, 0], nominal.frf[:, 0, 0]
    ok = (np.abs(g_m) > 0) & (np.abs(g_n) > 0)
    lines = np.asarray(measured.lines)[ok]
    u_power = np.mean([np.abs(np.fft.rfft(u_list[i][:period])[lines]) ** 2 for i in picks], axis=0)
    return StiffnessChange(omega=2 * np.pi * lines * fs / period,
                           delta=1 / g_m[ok] - 1 / g_n[ok],
                           weight=np.abs(g_m[ok] * g_n[ok]) ** 2 * u_power)


def _attached_oscillator(omega, w2, zeta):
    """Dynamic stiffness per unit attached mass of an oscillator of natural
    frequency ``w2`` and damping ratio ``zeta`` hung on the structure."""
    spring = w2**2 + 2j * zeta * w2 * omega
    return -omega**2 * spring / (spring - omega**2)


def second_mode_start(change, nominal, bounds, n_grid=400):
    """Best ``theta = (mass ratio, frequency ratio, damping ratio)`` of an
    attached oscillator for the measured stiffness change: a dense grid in
    frequency and damping, the mass by weighted linear least squares (the
    change is proportional to it).  When no attached oscillator explains
    half the change, the start is a negligible mode: the smallest mass at
    the lowest frequency (far below the band it is a spring of next to no
    stiffness), well damped so that its steady state is found at once.
    The grid's best would be a barely damped corner, which costs long
    steady-state searches and tells nothing, and the listed starts are
    real modes the data do not show, from which the optimiser wanders
    along directions the cost barely depends on."""
    w1 = np.sqrt(nominal.stiffness / nominal.mass)
    lo, hi = bounds
    ratios = np.geomspace(max(lo[1], 1e-3), hi[1], n_grid)
    zetas = np.geomspace(max(lo[2], 1e-3), hi[2], 12)
    w = change.weight
    best, best_cost = None, np.inf
    for zeta in zetas:
        for r in ratios:
            h = _attached_oscillator(change.omega, r * w1, zeta)
            hh = np.sum(w * np.abs(h) ** 2)
            if hh == 0:
                continue
            mass = np.sum(w * np.real(np.conj(h) * change.delta)) / hh
            mass = float(np.clip(mass, lo[0] * nominal.mass, hi[0] * nominal.mass))
            cost = np.sum(w * np.abs(change.delta - mass * h) ** 2)
            if cost < best_cost:
                best, best_cost = np.array([mass / nominal.mass, r, zeta]), cost
    if best_cost > 0.5 * np.sum(w * np.abs(change.delta) ** 2):
        return np.array([lo[0], lo[1], 0.3])
    return best


def _recalibration_basis(change, nominal, scales, free=("mass", "damping", "stiffness")):
    """The stiffness change per unit ``theta`` of each freed nominal
    parameter: ``-w^2``, ``i w`` and 1 times its
    :func:`~sklearn_pnlss.gap.candidates.effect.recalibration_unit`."""
    per_unit = {"mass": -change.omega**2, "damping": 1j * change.omega, "stiffness": np.ones(change.omega.shape)}
    columns = [per_unit[name] * recalibration_unit(name, nominal, scales) for name in free]
    return np.stack(columns, axis=1).astype(complex) if free else np.zeros((change.omega.size, 0))


def _real_weighted(change, basis):
    """The weighted fit of ``basis`` to the change as a real problem:
    columns and target stacked real over imaginary parts."""
    w = np.sqrt(change.weight)
    basis = np.asarray(basis)
    basis = w[:, None] * (basis[:, None] if basis.ndim == 1 else basis)
    return np.concatenate([basis.real, basis.imag]), np.concatenate([(w * change.delta).real, (w * change.delta).imag])


def _weighted_solve(change, basis):
    """Real coefficients of ``basis`` fitting the change (weighted), and the
    weighted cost left."""
    A, b = _real_weighted(change, basis)
    coef = np.linalg.lstsq(A, b, rcond=None)[0]
    return coef, float(np.sum((A @ coef - b) ** 2))


def recalibration_start(change, nominal, scales):
    """``theta`` of the refitted mass, damping and stiffness: the stiffness
    change ``dk - w^2 dm + i w dc`` is linear in them."""
    return _weighted_solve(change, _recalibration_basis(change, nominal, scales))[0]


def second_mode_joint_start(change, nominal, scales, bounds, free, n_grid=400):
    """:func:`second_mode_start` with the freed nominal parameters solved
    together with the attached mass at every grid point: ``theta`` of the
    mode followed by theirs.  A nominal that is off changes the dynamic
    stiffness by ``dk - w^2 dm + i w dc`` too, which the mode alone would
    try to explain."""
    w1 = np.sqrt(nominal.stiffness / nominal.mass)
    lo, hi = bounds
    linear = _recalibration_basis(change, nominal, scales, free)
    recal, recal_cost = _weighted_solve(change, linear)
    trials = TrialColumns(*_real_weighted(change, linear))
    # every grid point's attached mode solved beside the freed parameters
    # at once (TrialColumns), the best one's coefficients solved again
    ratios = np.geomspace(max(lo[1], 1e-3), hi[1], n_grid)
    zetas = np.geomspace(max(lo[2], 1e-3), hi[2], 12)
    costs = np.array([trials.costs(_real_weighted(change, _attached_oscillator(change.omega[:, None],
                                                                                ratios * w1, zeta))[0])
                      for zeta in zetas])
    best, best_cost = None, np.inf
    if np.isfinite(costs).any():
        i, j = np.unravel_index(np.nanargmin(costs), costs.shape)
        h = _attached_oscillator(change.omega, ratios[j] * w1, zetas[i])
        coef, best_cost = _weighted_solve(change, np.column_stack([h, linear]))
        mass = float(np.clip(coef[0], lo[0] * nominal.mass, hi[0] * nominal.mass))
        best = np.concatenate([[mass / nominal.mass, ratios[j], zetas[i]], coef[1:]])
    if best is None or best_cost > 0.5 * recal_cost:
        # no mode explains half of what the refit leaves: a negligible one
        return np.concatenate([[lo[0], lo[1], 0.3], recal])
    return best
