"""Fit an effect's parameters by simulation error on the training signals.

Few parameters (one to six) and an expensive, smooth simulation: a bounded
trust-region least-squares (scipy's ``trf``) with a forward-difference
Jacobian in the dimensionless parameters, started from the best of a few
listed starting points.  A start or trial point whose simulation diverges or
is not physical gets a large residual, so the trust region shrinks away from
it; it is never returned.
"""
import time
from collections import namedtuple
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from .simulate import FIT_MAX_PERIODS, simulate_sensitivities, simulate_signals
from ..readings import misfit
from ..settings import SETTINGS

__all__ = ["EffectFit", "meaningful_ftol", "fit_effect", "refine_fit", "at_rate", "signal_errors", "pooled_mse",
           "parameter_information", "parameter_covariance"]

# Residual given to a trial point that diverges or is not physical, relative
# to the displacement scale: far above any real misfit.
_PENALTY = 1e3
_FD_STEP = 1e-5


@dataclass
class EffectFit:
    """An effect fitted to the training signals.

    Attributes
    ----------
    effect : Effect
    theta : ndarray
        Dimensionless parameters.
    physical : dict
        Physical parameter values.
    train_mse : float
        Mean squared training simulation error, m^2 (at the reporting rate
        once ``refined``, at the fitting rate before).
    n_evaluations : int
        Simulations of the training set used.
    converged : bool
    message : str
    seconds : float
        Wall time of the fit.
    data_starts : list of ndarray
        The data's starts that were best at the fitting rate: a refinement
        at the reporting rate tries them again (see :func:`refine_fit`).
    refined : bool
        Whether the fit holds at the reporting rate (refined there, or
        fitted there in the first place).
    coarse_mse : float
        Mean squared training error at the fitting rate, before any
        refinement: candidates are compared with each other there (a
        coarse set's correction of the nominal's discretisation error
        leaves every candidate a like floor that a refined fit does not).
    information : ndarray of shape (n_params, n_params) or None
        The parameters' Gauss-Newton information on the training signals
        (:func:`parameter_information`), filled once the diagnosis' fits
        are final: the report's parameter covariance
        (:func:`parameter_covariance`) needs no training data.
    progress_db : float
        Training gain per evaluation (dB) over the last half of the last
        solve's evaluations: what another budget can be expected to bring
        (0 when it converged, or nothing was solved).
    """

    effect: object
    theta: np.ndarray
    physical: dict
    train_mse: float
    n_evaluations: int
    converged: bool
    message: str
    seconds: float = 0.0
    data_starts: list = field(default_factory=list)
    refined: bool = True
    coarse_mse: float = None
    information: np.ndarray = None
    progress_db: float = 0.0


#: How a solve stopped: converged, the solver's message, and the training
#: gain per evaluation (dB) over its last half (see ``EffectFit.progress_db``).
Stop = namedtuple("Stop", "converged message progress_db")
NOTHING_SOLVED = Stop(True, "nothing to fit", 0.0)


def _progress_db(costs, converged):
    """Gain per evaluation (dB) of the best cost so far over the last half
    of ``costs`` (a solve's evaluations in order); 0 once converged."""
    if converged or len(costs) < 2:
        return 0.0
    best = np.minimum.accumulate(costs)
    half = len(best) // 2
    return float(10 * np.log10(best[half - 1] / best[-1]) / (len(best) - half)) if best[-1] > 0 else 0.0


class _Objective:
    """Residuals of one effect on the training set, counting simulations."""

    def __init__(self, effect, nominal, scales, signals, y_meas, offsets=False):
        self.effect, self.nominal, self.scales, self.offsets = effect, nominal, scales, offsets
        self.signals, self.y_meas = signals, y_meas
        self.size = sum(y.size for y in y_meas)
        self.n_evaluations = 0
        # A response this large misfits by more than the penalty whatever
        # the data: stop its simulation at the first period that shows it
        # (a hysteresis trial point running away to metres otherwise
        # integrates every period allowed, most of a fit's time).
        self.max_abs = 2 * _PENALTY * scales.displacement + max(np.max(np.abs(y)) for y in y_meas)
        # the steady states of the last point simulated: its Jacobian (the
        # trust region asks at the point it has just accepted) starts there
        self._steady = (None, None)

    def __call__(self, theta):
        self.n_evaluations += 1
        states = []
        try:
            osc, transform, _ = self.effect.simulator(theta, self.nominal, self.scales)
            y_sim = simulate_signals(osc, self.signals, transform, max_periods=FIT_MAX_PERIODS,
                                     max_abs=self.max_abs, steady_states=states)
        except (ValueError, FloatingPointError, ZeroDivisionError):
            return np.full(self.size, _PENALTY)
        self._steady = (np.asarray(theta, float).tobytes(), states)
        r = np.concatenate([misfit(ys, ym, self.offsets) for ys, ym in zip(y_sim, self.y_meas)])
        r /= self.scales.displacement
        if not np.all(np.isfinite(r)) or np.max(np.abs(r)) > _PENALTY:
            return np.full(self.size, _PENALTY)
        return r

    def subset(self, index):
        """The same objective on the training signals at ``index``."""
        return _Objective(self.effect, self.nominal, self.scales, self.signals.subset(index),
                          [self.y_meas[i] for i in index], self.offsets)

    def jacobian(self, theta, r0, lower, upper):
        """Jacobian of the residuals at ``theta`` (``r0`` its residuals):
        from the integrator's sensitivities where they apply, by forward
        differences of the simulation otherwise."""
        J = self._sensitivity_jacobian(theta, r0, lower, upper)
        return self._difference_jacobian(theta, r0, lower, upper) if J is None else J

    def _difference_jacobian(self, theta, r0, lower, upper, columns=None):
        J = np.zeros((r0.size, theta.size))
        for i in range(theta.size) if columns is None else columns:
            step = _step(theta, i, upper)
            t = theta.copy()
            t[i] += step
            J[:, i] = (self(t) - r0) / step
        return J

    def _sensitivity_jacobian(self, theta, r0, lower, upper):
        """The Jacobian from one simulation with sensitivities: the
        residuals' derivatives by the oscillator's physical parameters
        (:func:`simulate_sensitivities`) times those parameters'
        derivatives by ``theta`` (differences of the effect's build, no
        simulation).  A parameter the oscillator does not see acts through
        the input transform (a delay, a saturation level) and is differenced
        by simulation.  None where the recursion does not apply."""
        try:
            osc, transform, _ = self.effect.simulator(theta, self.nominal, self.scales)
            physical = _physical_derivatives(self.effect, theta, osc, self.nominal, self.scales, upper)
            if physical is None or osc.time_varying:
                return None
            key, states = self._steady
            states = states if key == np.asarray(theta, float).tobytes() else None
            dy = simulate_sensitivities(osc, self.signals, transform, max_periods=FIT_MAX_PERIODS,
                                        max_abs=self.max_abs, steady_states=states)
        except (ValueError, FloatingPointError, ZeroDivisionError):
            return None
        self.n_evaluations += 1
        blocks = [d @ physical for d in dy]
        if self.offsets:
            blocks = [b - b.mean(axis=0) for b in blocks]
        J = np.concatenate(blocks) / self.scales.displacement
        through_input = [i for i in range(theta.size) if transform is not None and not np.any(physical[:, i])]
        if through_input:
            J[:, through_input] = self._difference_jacobian(theta, r0, lower, upper, through_input)[:, through_input]
        return J


def _step(theta, i, upper):
    """Forward-difference step of parameter ``i``, backward at its upper bound."""
    step = _FD_STEP * max(1.0, abs(theta[i]))
    return -step if theta[i] + step > upper[i] else step


def _physical_derivatives(effect, theta, osc, nominal, scales, upper):
    """Derivatives of the oscillator's physical parameters
    (:attr:`~sklearn_pnlss.physics.Oscillator.parameter_vector`) by
    ``theta``: differences of the effect's build, which costs no
    simulation.  None when a step changes the oscillator's structure."""
    base = osc.parameter_vector
    out = np.empty((base.size, theta.size))
    for i in range(theta.size):
        step = _step(theta, i, upper)
        t = theta.copy()
        t[i] += step
        moved = effect.simulator(t, nominal, scales)[0].parameter_vector
        if moved.size != base.size:
            return None
        out[:, i] = (moved - base) / step
    return out


def _solve(obj, theta0, lower, upper, max_nfev, ftol):
    """``obj`` minimised from ``theta0``: ``(theta, Stop, cost)``."""
    cache, costs = {}, []

    def fun(theta):
        key = theta.tobytes()
        if key not in cache:
            cache.clear()  # the Jacobian asks for the last point only
            cache[key] = obj(theta)
            costs.append(float(np.sum(cache[key] ** 2)))
        return cache[key]

    def jac(theta):
        return obj.jacobian(theta, fun(theta), lower, upper)

    # Keep the start strictly inside the bounds, as trf requires.
    span = upper - lower
    theta0 = np.clip(theta0, lower + 1e-9 * span, upper - 1e-9 * span)
    res = least_squares(fun, theta0, jac=jac, bounds=(lower, upper), method="trf",
                        x_scale="jac", max_nfev=max_nfev, xtol=1e-6, ftol=ftol)
    converged = res.status > 0
    return res.x, Stop(converged, res.message, _progress_db(costs, converged)), float(np.sum(fun(res.x) ** 2))


def _by_signal(a, y_meas):
    """``a`` (residuals, or Jacobian rows, of all training signals in
    order) split into each signal's part (their lengths those of ``y_meas``)."""
    return np.split(a, np.cumsum([y.size for y in y_meas])[:-1])


def per_signal_mse(r, y_meas):
    """Mean squared residual of each training signal, ``r`` being the
    residuals of all of them in order (their lengths those of ``y_meas``)."""
    return np.array([np.mean(part**2) for part in _by_signal(r, y_meas)])


def outlying_signals(values, ratio=SETTINGS.jump_ratio):
    """Indices of the training signals whose ``values`` (a misfit, a
    sensitivity) are ``ratio`` times the median signal's or more (empty
    with fewer than three signals: no median to compare with)."""
    values = np.asarray(values, float)
    if values.size < 3:
        return []
    return [int(i) for i in np.flatnonzero(values >= ratio * np.median(values))]


def per_signal_sensitivity(J, y_meas):
    """How sharply each training signal's misfit moves with the parameters,
    relative to the signal's size: the squared norm of its rows of the
    Jacobian ``J`` over its squared norm (a signal twice as large is not
    twice as sensitive for that)."""
    return np.array([np.sum(p**2) / max(np.sum(np.square(y)), 1e-300) for p, y in zip(_by_signal(J, y_meas), y_meas)])


def stalled_near_noise(converged, mse, noise_variance):
    """Whether a fit stopped on its budget with its misfit ``mse`` within
    ``SETTINGS.needle_reach_db`` of the noise: the one case where a needle signal
    may hold it back.  A fit far above the noise misses structure, which
    leaving a signal out cannot supply (and the sensitivity's simulations
    would only cost time: 152 -> 304 s on a clean stiff backlash when every
    stopped fit was tried).  Without a noise estimate there is no gate."""
    return bool(not converged and noise_variance is not None
                and mse <= noise_variance * 10 ** (SETTINGS.needle_reach_db / 10))


def _refit_without_outliers(obj, theta, r, stalled, lower, upper, max_nfev, ftol):
    """``theta`` (residuals ``r``) refitted on the training signals that
    neither jumped nor make the misfit a needle, kept when it lowers the
    cost on all of them: ``(theta, its residuals, the refit's Stop or None,
    simulations used)``.

    A response that jumps between coexisting steady states (a stiff spring
    engaging beyond a clearance) makes the simulation error a needle: 0.1 %
    off in the spring rate and the clearance, one of four multisine
    realisations settles on the other branch, 30 dB above the noise, and its
    misfit changes by jumps that stall the trust region there.  The other
    signals' error is smooth down to the needle; fitted on them alone the
    parameters reach it, and the jumped signal then settles where the data
    did (measured: -67 -> -103 dB on that signal, the noise floor).

    A realisation on the same branch as the data but close to where it
    would jump stalls the fit as well, without standing out in misfit: its
    valley is far narrower than the others' (10 times their sensitivity,
    100 times squared, on a stiff backlash), about as narrow as the
    Jacobian's difference step, and the trust region crawls along it.  So
    when the fit is ``stalled`` (stopped on its budget close to the noise)
    and no signal jumped, the signal whose sensitivity stands out is left
    out instead (measured: 20 iterations gained 2 % of the cost on all four
    signals; on the other three the refit reached the noise floor in 24
    simulations, and so did the fourth).
    """
    left_out, n_used = outlying_signals(per_signal_mse(r, obj.y_meas)), 0
    if not left_out and stalled:
        left_out = outlying_signals(per_signal_sensitivity(obj.jacobian(theta, r, lower, upper), obj.y_meas))
        n_used = theta.size
    if not left_out:
        return theta, r, None, n_used
    sub = obj.subset([i for i in range(len(obj.y_meas)) if i not in left_out])
    refit, stop, _ = _solve(sub, theta, lower, upper, max_nfev, ftol)
    r_refit = obj(refit)
    n_used += sub.n_evaluations + 1  # and the refit's cost on all signals
    if np.sum(r_refit**2) < np.sum(r**2):
        return refit, r_refit, stop, n_used
    return theta, r, None, n_used


def parameter_information(fit, nominal, scales, signals, y_meas, offsets=False):
    """The Gauss-Newton information ``J^T J`` of a fit's dimensionless
    parameters on its training signals: ``J`` the Jacobian of the training
    residuals in displacement scales (one simulation with the integrator's
    sensitivities, or one per parameter where it differences).  What the
    data say about the parameters, before the noise is known
    (:func:`parameter_covariance`)."""
    obj = _Objective(fit.effect, nominal, scales, signals, y_meas, offsets)
    theta = np.asarray(fit.theta, float)
    lower, upper = fit.effect.bounds
    J = obj.jacobian(theta, obj(theta), lower, upper)
    return J.T @ J


def parameter_covariance(fit, scales, noise):
    """Covariance of a fit's dimensionless parameters, as far as its
    training signals determine them (its ``information``, see
    :func:`parameter_information`) under the output ``noise``
    (:class:`~sklearn_pnlss.gap.verdict.noise_floor.NoiseFloor`).

    The Gauss-Newton approximation ``sigma^2 (J^T J)^+ / nu``: ``sigma^2``
    the noise variance and ``nu`` its independent samples per sample
    (band-limited noise holds fewer than its sample count).  The noise's
    variance, not the residual's: a candidate that misses the data is not
    made uncertain by its own misfit (whose spread would then excuse it on
    a validation signal).  A direction the data do not see gets the
    pseudo-inverse's zero, not an infinite spread.
    """
    variance = noise.variance / scales.displacement**2
    return variance * np.linalg.pinv(fit.information) / max(noise.dof_per_sample, 1e-3)


def meaningful_ftol(noise, n_samples):
    """Relative cost decrease below which an iteration only fits noise.

    With the misfit at the noise level the cost is about ``nu N`` noise
    units (``nu`` effective degrees of freedom per sample); a decrease
    smaller than a chi-square(1) quantile (4 units) does not tell one
    parameter value from another, and chasing it lets the optimiser wander
    along directions the data do not determine (a negligible second mode
    drifting to a barely damped corner).  Above the noise the same
    fraction is a still smaller change in dB.  1e-8 without a noise floor.
    """
    if noise is None:
        return 1e-8
    return max(1e-8, 4.0 / max(noise.dof_per_sample * n_samples, 1.0))


def _defect_corrected(obj, fine_signals, theta, lower, upper, max_nfev, ftol):
    """Refine a fit of the coarse-rate objective ``obj`` by defect
    correction: ``(objective, theta, simulations, the last round's Stop or
    None)``.

    Each round carries the model's own discretisation error at the latest
    estimate (fine minus coarse) into the coarse simulations and refits:
    the coarse objective then equals the fine one at that estimate, and the
    bias left is second order in how far the round moves.  One round is not
    enough for a strong nonlinearity: a cubic spring at 1e8 N/m^3 ended 4
    standard errors off in damping after it (its sweep's jump 8 dB above
    the noise); a second round lands on the fine-rate optimum.  Rounds stop
    when one lowers the cost by less than ``ftol`` (its start is then the
    fine optimum to the noise) or after ``SETTINGS.defect_rounds``.  The objective
    returned is the last round's (``obj`` if none could run).
    """
    plain, n_used, solved = obj.signals.without_correction(), 0, None
    for _ in range(SETTINGS.defect_rounds):
        osc, transform, _ = obj.effect.simulator(theta, obj.nominal, obj.scales)
        try:
            fine = simulate_signals(osc, fine_signals, transform)
            corrected = obj.signals.with_correction(
                [f - c for f, c in zip(fine, simulate_signals(osc, plain, transform))])
            round_obj = _Objective(obj.effect, obj.nominal, obj.scales, corrected, obj.y_meas, obj.offsets)
            start_cost = float(np.sum(round_obj(theta) ** 2))
            new, stop, cost = _solve(round_obj, theta, lower, upper, max(3, max_nfev // 4), ftol)
        except (ValueError, FloatingPointError):
            break  # keep the estimate so far
        n_used += round_obj.n_evaluations + 2
        obj, theta, solved = round_obj, new, stop
        if start_cost - cost <= ftol * start_cost:
            break
    return obj, theta, n_used, solved


def _start_costs(obj, starts, n_listed):
    """Training cost of each start: the ``n_listed`` listed starts and the
    ``SETTINGS.screened_starts`` data starts best on the first training signal are
    evaluated on all of them, the others get infinity."""
    n_signals = len(obj.y_meas)
    if len(starts) - n_listed <= SETTINGS.screened_starts or n_signals < 2:
        return np.array([np.sum(obj(s) ** 2) for s in starts])
    screen = obj.subset([0])
    first = [np.sum(screen(s) ** 2) for s in starts[n_listed:]]
    kept = list(range(n_listed)) + [n_listed + int(i) for i in np.argsort(first)[:SETTINGS.screened_starts]]
    costs = np.full(len(starts), np.inf)
    costs[kept] = [np.sum(obj(starts[i]) ** 2) for i in kept]
    obj.n_evaluations += -(-screen.n_evaluations // n_signals)  # in simulations of the whole set
    return costs


def fit_effect(effect, nominal, scales, signals, y_meas, *, max_nfev=30, fine_signals=None, clues=None,
               ftol=1e-8, offsets=False, noise_variance=None):
    """Fit one effect by simulation error.

    Parameters
    ----------
    effect : Effect
    nominal : Oscillator
    scales : Scales
    signals : SignalSet
        Training inputs.
    y_meas : list of ndarray
        Measured training outputs (same lengths as the inputs).
    max_nfev : int, default=30
        Trust-region iterations at most.
    fine_signals : SignalSet, default=None
        The training inputs at the reporting rate when ``signals`` is a
        coarse set (see :meth:`SignalSet.coarse`): the fit is then refined
        with the fitted model's own discretisation error.
    clues : DataClues, default=None
        Readings of the training data from which some effects take one
        more start (see :mod:`sklearn_pnlss.gap.candidates.clues`).
    ftol : float, default=1e-8
        Stop when an iteration lowers the cost by less than this fraction
        (see :func:`meaningful_ftol`).
    offsets : bool, default=False
        Grant each signal its best constant output offset (see
        :func:`~sklearn_pnlss.gap.fitting.simulate.misfit`).
    noise_variance : float, default=None
        The measured output's noise variance, m^2, where the data give it:
        a fit that stops on its budget within ``SETTINGS.needle_reach_db`` of it is
        looked at for a signal that stalls it (see
        :func:`_refit_without_outliers`).  One far above the noise misses
        structure, which leaving a signal out cannot supply (on the
        benchmark's clean stiff backlash, looking at every candidate doubled
        the diagnosis' time for nothing).

    Returns
    -------
    EffectFit
    """
    start = time.perf_counter()
    obj = _Objective(effect, nominal, scales, signals, y_meas, offsets)
    lower, upper = effect.bounds
    data_starts = effect.data_starts(clues, nominal, scales)
    starts = [np.clip(s, lower, upper) for s in effect.starts] + data_starts
    costs = _start_costs(obj, starts, len(effect.starts))
    theta = starts[int(np.argmin(costs))]
    stop, cost = NOTHING_SOLVED, float(np.min(costs))
    if effect.n_params:
        theta, stop, cost = _solve(obj, theta, lower, upper, max_nfev, ftol)
        if cost > min(costs):  # never worse than the best start
            theta, cost = starts[int(np.argmin(costs))], float(np.min(costs))
    coarse_mse = cost / obj.size * scales.displacement**2
    n_evaluations = obj.n_evaluations
    best_data_starts = [data_starts[i] for i in np.argsort(costs[len(effect.starts):])[:SETTINGS.fine_data_starts]
                        if np.isfinite(costs[len(effect.starts) + i])]
    if effect.n_params and fine_signals is not None and signals.correction is not None:
        obj, theta, n_used, solved = _defect_corrected(obj, fine_signals, theta, lower, upper, max_nfev, ftol)
        n_evaluations += n_used
        stop = solved or stop
        coarse_cost = np.sum(obj(theta) ** 2)
        fine_obj = _Objective(effect, nominal, scales, fine_signals, y_meas, offsets)
        # The data's own starts, read off the measured motion, hold at any
        # rate; the coarse optimum may not.  (The few best at the coarse
        # rate: a profile gives dozens.)
        fine_starts = [theta] + best_data_starts
        fine_costs = [np.sum(fine_obj(t) ** 2) for t in fine_starts]
        best = int(np.argmin(fine_costs))
        if best > 0 or fine_costs[0] > SETTINGS.fine_mismatch * coarse_cost:
            # The coarse rate's correction no longer holds: a strong
            # nonlinearity whose steady state (or a sweep's jump) depends on
            # the integration rate settles on another branch at each rate,
            # or its minimum is a valley narrower than the correction's
            # reach (a stiff backlash: 1e-4 wide in the spring rate, moved
            # by 2e-3 at a fifth of the rate).  Fit at the reporting rate
            # itself, from the better of the coarse optimum and the data's
            # starts.
            theta, stop, _ = _solve(fine_obj, fine_starts[best], lower, upper, max_nfev, ftol)
        n_evaluations += fine_obj.n_evaluations
        obj = fine_obj
    r = obj(theta)
    if effect.n_params:
        stalled = stalled_near_noise(stop.converged, np.mean(r**2) * scales.displacement**2, noise_variance)
        theta, r, refit, n_used = _refit_without_outliers(obj, theta, r, stalled, lower, upper, max_nfev, ftol)
        stop = refit or stop
        n_evaluations += n_used
    mse = float(np.mean(r**2)) * scales.displacement**2
    _, _, physical = effect.simulator(theta, nominal, scales)
    return EffectFit(effect, theta, physical, mse, n_evaluations, bool(stop.converged), str(stop.message),
                     time.perf_counter() - start, best_data_starts,
                     refined=fine_signals is not None or signals.correction is None, coarse_mse=coarse_mse,
                     progress_db=stop.progress_db)


def signal_errors(fit, nominal, scales, signals, y_meas, offsets=False):
    """Mean squared error (m^2) of ``fit`` on each of ``signals`` (one
    simulation)."""
    r = _Objective(fit.effect, nominal, scales, signals, y_meas, offsets)(fit.theta)
    return per_signal_mse(r, y_meas) * scales.displacement**2


def pooled_mse(errors, y_meas):
    """The mean squared error over all of ``y_meas`` from each signal's
    (``errors``, as :func:`signal_errors` gives them)."""
    return float(np.average(errors, weights=[y.size for y in y_meas]))


def at_rate(fit, nominal, scales, signals, y_meas, offsets=False):
    """``fit`` with its ``coarse_mse`` taken on ``signals`` (one
    simulation): a fit made on another coarse set compared with those made
    on this one."""
    return replace(fit, coarse_mse=pooled_mse(signal_errors(fit, nominal, scales, signals, y_meas, offsets), y_meas))


def refine_fit(fit, nominal, scales, signals, y_meas, *, fine_signals, clues=None, **kwargs):
    """Carry a fit made at the fitting rate alone (:func:`fit_effect`
    without ``fine_signals``) on to the reporting rate: from its optimum
    and the data starts that were best there, with the model's own
    discretisation error carried over and checked at the reporting rate,
    as :func:`fit_effect` does in one go.  The simulations and the time
    are those of both stages."""
    best = np.array(fit.data_starts) if fit.data_starts else None
    warm = fit.effect.variant(starts=[fit.theta], data_starts=[] if best is None else best)
    more = fit_effect(warm, nominal, scales, signals, y_meas, fine_signals=fine_signals, clues=clues, **kwargs)
    return replace(more, effect=fit.effect, n_evaluations=fit.n_evaluations + more.n_evaluations,
                   seconds=fit.seconds + more.seconds, coarse_mse=fit.coarse_mse)
