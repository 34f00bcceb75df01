"""The fitting engine: Levenberg-Marquardt on the simulation error of a
state-space model, with validation and trusted ranges.

Every nonlinear estimator of the library fits through :func:`optimise`; what
differs between them is only the start model they hand it (see
:mod:`sklearn_pnlss.estimators`). The engine works on a
:class:`~sklearn_pnlss.statespace.scaled.ScaledModel`: it fits the
normalised model on normalised signals and scores validation signals in the
user's units.

Levenberg-Marquardt fits the plain polynomial. Every iterate scored on
validation signals, and the returned model, carry the trusted range of
their nonlinearity (the range its variables cover along the simulation of
the training segments, widened by ``range_margin``), continued outside it as
``extrapolation`` says; inside the range nothing changes. The training data
lie inside that range by construction, so the fit itself is unchanged.
"""
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from ..frequency.noise import signal_noise_variances
from ..metrics import to_db
from ..utils.validation import is_periodic
from .levenberg_marquardt import levenberg_marquardt
from .model_base import MAX_STEADY_PERIODS, RUNAWAY_FACTOR, DivergenceError
from .objective import SimulationError
from .segments import make_segments, transient_length

__all__ = [
    "AMPLIFIED_VALIDATION", "FitSettings", "LMFit", "NewInputRunaway", "TIME_DOMAIN_WEIGHTINGS",
    "iteration_listener", "optimise", "relative_weights", "simulation_objectives", "trusted_model",
]

# The weightings that act in time (per sample, beside ``time_weight``); the
# others weight the DFT bins of a period.
TIME_DOMAIN_WEIGHTINGS = (None, "relative")

# An iterate (or a start) that runs away (diverges, or leaves its trusted
# range by more than its width) on the validation inputs amplified by this
# factor counts as failed: a returned model must stay sane somewhat above the
# level it was validated at.
AMPLIFIED_VALIDATION = 1.2

# Callbacks told of every Levenberg-Marquardt iteration (see iteration_listener).
_LISTENERS = []


@contextmanager
def iteration_listener(callback):
    """Within the block, ``callback(iteration, cost_db)`` is called after
    every Levenberg-Marquardt iteration of every fit (all threads): how an
    application shows progress inside long fits. ``cost_db`` is the rms of
    the weighted normalised error in dB."""
    _LISTENERS.append(callback)
    try:
        yield
    finally:
        _LISTENERS.remove(callback)


@dataclass(frozen=True)
class FitSettings:
    """How a model is fitted: the estimators' fit parameters of the same
    names (see :class:`~sklearn_pnlss.PNLSSRegressor`).

    ``n_threads``: threads over the training segments.
    ``new_inputs``: inputs (user units, one period each) of the training
    kind and level the kept iterate must not run away on (see
    :func:`~sklearn_pnlss.statespace.new_inputs.random_phase_inputs` and
    :func:`optimise`). ``training_periods``: one period of each periodic
    training input (user units), whose response, the input repeated from
    rest, the kept iterate must settle into a periodic steady state on.
    ``check_records``: the user's inputs (user units, any length) of other
    kinds at the training levels, each simulated from rest, that the kept
    iterate must not run away on either. ``check_outputs``: the outputs
    measured with them (user units), or empty: the kept iterate must then
    also simulate each record from rest no worse than the fit's start does.
    """

    period: int | None = None
    average_periods: bool = True
    weighting: str | None = None
    band: tuple | None = None
    max_iter: int = 100
    tol: float = 1e-8
    n_transient: int | str = "auto"
    extrapolation: str = "hold"
    range_margin: float = 0.0
    stable_at_rest: bool = False
    verbose: int = 0
    n_threads: int = 1
    new_inputs: tuple = field(default=(), compare=False, repr=False)
    training_periods: tuple = field(default=(), compare=False, repr=False)
    check_records: tuple = field(default=(), compare=False, repr=False)
    check_outputs: tuple = field(default=(), compare=False, repr=False)

    def period_of(self, U):
        """``period`` when ``U`` is a periodic steady-state signal, else None."""
        return self.period if is_periodic(U.shape[0], self.period) else None


@dataclass
class LMFit:
    """Outcome of one fit (see :func:`optimise`)."""

    model: object  # ScaledModel
    n_iter: int
    best_iteration: int
    cost_history: np.ndarray
    validation_history: np.ndarray | None
    validation_error: float  # dB, best over the iterations; NaN without validation
    kept_cost: float = np.nan  # the kept iterate's cost (its stage's objective)
    # set when the preferred iterate ran away on the settings' new inputs
    new_input_runaway: "NewInputRunaway | None" = None


@dataclass(frozen=True)
class NewInputRunaway:
    """The preferred iterate of a fit ran away on new inputs of the
    training kind or on the user's check records, or did not settle on its
    own training inputs (see :func:`optimise`)."""

    iteration: int  # the preferred iterate
    n_runaway: int  # new inputs it ran away on
    n_inputs: int
    kept_iteration: int | None  # None: no iterate passed; the preferred one was kept
    n_unsettled: int = 0  # training inputs whose response it did not settle on
    n_training: int = 0
    runaway_records: tuple = ()  # the check records (places in X_check) it ran away on, for the warning to name
    n_records: int = 0
    worse_records: tuple = ()  # the check records it simulated worse than the fit's start (with y_check)

    def message(self, ranking):
        """The warning an estimator gives; ``ranking``: how the iterates
        were ordered ("the latest", "the best on the validation signals")."""
        kept = (f"iterate {self.kept_iteration} is kept instead, {ranking} of those that do not"
                if self.kept_iteration is not None else "so do the other iterates probed, so it is kept all the same")
        faults = []
        if self.n_runaway:
            faults.append(f"runs away on {self.n_runaway} of {self.n_inputs} new random-phase realisations of the "
                          "training inputs (it leaves the range its nonlinearity was fitted on by more than that "
                          "range's width)")
        if self.runaway_records:
            named = ", ".join(f"X_check[{i}]" for i in self.runaway_records)
            faults.append(f"runs away on {len(self.runaway_records)} of the {self.n_records} check records ({named}) "
                          "simulated from rest")
        if self.worse_records:
            named = ", ".join(f"X_check[{i}]" for i in self.worse_records)
            faults.append(f"simulates {len(self.worse_records)} of the {self.n_records} check records ({named}) from "
                          "rest worse than the fit's start (their y_check), a jump to another response or a "
                          "drift the fit's signals did not show")
        if self.n_unsettled:
            faults.append(f"does not settle into a periodic response on {self.n_unsettled} of its {self.n_training} "
                          f"periodic training inputs repeated from rest (within {MAX_STEADY_PERIODS} periods: it "
                          "oscillates by itself, which its fit, a period after a short transient, did not see)")
        return (
            f"The fitted model (iterate {self.iteration}) {'; and '.join(faults)}; {kept}. The training data "
            "constrain this model too little there: give more realisations or kinds of input at these levels, "
            "validation signals (X_val, y_val), or a smaller model."
        )


def simulation_objectives(start, X_list, y_list, settings, time_weights=None):
    """The stages of a fit: the (time-weighted) simulation error, then the
    frequency-weighted one when ``settings.weighting`` asks for it.

    Parameters
    ----------
    start : ScaledModel
        Gives the scales that normalise the signals and the linear part
        whose slowest pole sets the transient (``n_transient="auto"``).
    X_list, y_list : list of ndarray
        Training signals in the user's units.
    settings : FitSettings
    time_weights : list of ndarray or None

    Returns
    -------
    list of SimulationError
    """
    Xn = [start.normalise_inputs(U) for U in X_list]
    yn = [start.normalise_outputs(Y) for Y in y_list]
    period = settings.period
    n_tr = transient_length(start.normalised.A, period) if period else 0
    # A record that is not periodic may not start from rest (cut from a
    # longer run): its initial state is read off its first samples, over the
    # slowest linear mode's decay, at every evaluation of the cost. Fitted
    # from rest instead, a WH2009 estimation record put 85 % of the cost in
    # its first 50 samples, a transient no model of the system makes.
    window = transient_length(start.normalised.A, max(U.shape[0] for U in Xn))
    if settings.n_transient != "auto":
        n_tr, window = int(settings.n_transient), 0
    freq_weight = frequency_weight(Xn, yn, settings)

    def objective(time_weights, freq_weight):
        return SimulationError(make_segments(
            Xn, yn, period=period, n_transient=n_tr if period else 0,
            n_skip=0 if settings.n_transient == "auto" else int(settings.n_transient),
            average=settings.average_periods, time_weights=time_weights, freq_weight=freq_weight,
            init_window=window, pieces=-(-settings.n_threads // len(Xn)),
        ), n_threads=settings.n_threads)

    # The noise-weighted cost, dominated by the quietest bins, has poor
    # basins far from its optimum: from the linear start, LM stalls well
    # above it (measured in tests/test_pnlss_fitting.py). Starting it from
    # the time-domain optimum reaches it; with each signal's error relative
    # to its power there, records of several levels count alike in it, as
    # each counts by its own noise in the weighted cost.
    if settings.weighting == "noise":
        time_weights = relative_weights(y_list)
    stages = [objective(time_weights, None)] if settings.weighting != "band" else []
    if freq_weight is not None:
        stages.append(objective(None, freq_weight))
    return stages


def relative_weights(y_list, time_weights=None):
    """Time weights that make each signal's squared error relative to its
    own output power, per output (``weighting="relative"``), times
    ``time_weights`` when given.

    Stacked records of different amplitude (the test levels of a structure)
    then count alike, as the benchmarks' NRMSE scores them; unweighted, the
    cost is the largest level's, and a model may fit the quiet ones badly
    (on the F-16's levels 1, 3, 5 and 7, level 7 carries 21 to 37 times
    level 1's power, by output). The weights are scaled by the mean power over
    the signals: with one signal (or signals of one level) nothing changes,
    and without ``time_weights`` None is returned (no weights at all).
    """
    power = np.array([np.var(Y, axis=0) for Y in y_list])  # (n_signals, n_outputs)
    silent = np.argwhere(power <= 0)
    if silent.size:
        i, k = silent[0]
        raise ValueError(
            f"weighting='relative' divides each signal's error by its output power, but output {k} of "
            f"training signal {i} is constant; drop that signal or use weighting=None."
        )
    scale = power.mean(axis=0) / power
    if time_weights is None and np.all(scale == 1.0):
        return None  # one level: unit weights would only cost a multiply per Jacobian block
    if time_weights is None:
        return [np.broadcast_to(s, Y.shape) for s, Y in zip(scale, y_list)]
    return [w * s for w, s in zip(time_weights, scale)]


def frequency_weight(Xn, yn, settings):
    """Callable ``(i, n_averaged)`` giving the weight per DFT bin of the
    periodic segment of signal ``i`` that averages ``n_averaged`` periods,
    or None (time domain). ``weighting="noise"``: each signal's own inverse
    noise variance (:func:`~sklearn_pnlss.frequency.noise.signal_noise_variances`)."""
    weighting, period, band = settings.weighting, settings.period, settings.band
    if weighting in TIME_DOMAIN_WEIGHTINGS:
        return None
    if period is None or not all(is_periodic(U.shape[0], period) for U in Xn):
        raise ValueError(
            f"weighting={weighting!r} weights DFT bins of a period: set period and "
            "pass steady-state signals of whole periods, or use weighting=None."
        )
    n_bins = period // 2 + 1
    lo, hi = (0, n_bins - 1) if band is None else map(int, band)
    if not 0 <= lo <= hi < n_bins:
        raise ValueError(
            f"band must be (first, last) DFT bins with 0 <= first <= last <= period // 2 = "
            f"{n_bins - 1}; got {band}."
        )
    in_band = np.zeros((n_bins, 1))
    in_band[lo : hi + 1] = 1.0
    if weighting == "band":
        return lambda i, n_averaged: np.repeat(in_band, yn[0].shape[1], axis=1)
    variances = signal_noise_variances(yn, period)
    if variances is None:
        raise ValueError(
            "weighting='noise' estimates the noise from the spread over periods: pass "
            "periodic signals with at least two periods, or use weighting='band'."
        )
    # A noiseless bin (simulated data) would get an infinite weight.
    floor = 1e-12 * np.mean([np.mean(v[lo : hi + 1]) for v in variances]) + np.finfo(float).tiny
    weights = [in_band / np.maximum(v, floor) for v in variances]
    return lambda i, n_averaged: weights[i] * n_averaged


def trusted_model(model, segments, settings, objective=None):
    """``model`` (normalised) with the trusted range of its nonlinearity
    along its simulation of the training ``segments`` (each from the state
    the cost starts it from), continued outside it as
    ``settings.extrapolation`` says. ``objective``: the SimulationError of
    those segments, whose last simulations are reused when they were of
    ``model``."""
    if settings.extrapolation == "polynomial":
        return model.without_bounds()
    path = model.segments_trajectory(segments) if objective is None else objective.trajectory(model)
    trusted = model.with_trusted_range(path, settings.range_margin)
    return replace(trusted, linear_extrapolation=True) if settings.extrapolation == "linear" else trusted


def optimise(start, objectives, settings, validation=None, max_iter=None):
    """Levenberg-Marquardt from ``start`` through each objective in turn.

    Each stage starts where the previous one ended and runs at most
    ``max_iter`` (default ``settings.max_iter``) iterations. Without
    validation signals the last iterate is kept; with them, the iterate
    with the lowest rms simulation error on them over all stages, an
    iterate that runs away on them (amplified by
    :data:`AMPLIFIED_VALIDATION`) counting as failed (checked for the
    iterates that would be kept: those better than the best so far). With
    ``settings.new_inputs``, the iterate so chosen is kept only if it does
    not run away on any of them either; else an earlier one in that order
    (back in time, or down the validation ranking) that does not, and the
    fit reports it (the training data are few for the model structure).
    With ``settings.stable_at_rest``, a start stable at rest
    (:meth:`~sklearn_pnlss.statespace.model_base.StateSpaceModel.stable_at_rest`)
    gives a fit stable at rest: a trial step that is not counts as failed,
    like one whose simulation diverges. Each step drops the
    model's ``n_null_directions`` (parameter directions that leave the
    output unchanged). Pure (nothing is modified), so that several starts
    can run in parallel threads.

    Parameters
    ----------
    start : ScaledModel
        Start model; the fit changes its normalised model's parameters.
    objectives : list of SimulationError
        From :func:`simulation_objectives` with the same scales.
    settings : FitSettings
    validation : tuple (X_list, y_list) of signals in user units, or None
    max_iter : int or None

    Returns
    -------
    LMFit
        ``model`` is a ScaledModel carrying its trusted range.

    Raises
    ------
    DivergenceError
        If ``start`` diverges on the training segments.
    """
    model = start.normalised
    max_iter = settings.max_iter if max_iter is None else max_iter
    best = {"err": np.inf}  # the best validation error so far
    done = 0  # iterations of the earlier stages
    segments = objectives[0].segments

    def validation_error(theta):
        if validation is None:
            return np.nan
        # the running stage's objective (bound when the callback runs):
        # its last simulations are this iterate's
        cand = trusted_model(model.with_theta(theta), segments, settings, objective)
        err, inputs = [], []
        for U, Y in zip(*validation):
            per, Un = settings.period_of(U), start.normalise_inputs(U)
            try:
                err.append(start.user_outputs(cand.simulate_signal(Un, per)) - Y)
            except DivergenceError:
                return np.inf
            inputs.append((Un, per))
        value = float(to_db(np.sqrt(np.mean(np.concatenate(err) ** 2))))
        # The amplified inputs decide only whether an iterate may be kept:
        # one no better than the best so far is not kept anyway, so it is
        # spared those simulations (as many again as the validation's own).
        if value < best["err"] and any(cand.runs_away(AMPLIFIED_VALIDATION * Un, per) for Un, per in inputs):
            return np.inf
        return value

    # (iteration over the stages, parameters, validation error, cost) of every iterate
    iterates = []

    def callback(it, theta, cost, lam):
        v = validation_error(theta)
        iterates.append((done + it, theta.copy(), v, cost))
        best["err"] = min(best["err"], v)
        cost_db = 10 * np.log10(cost / n_res)
        for listener in tuple(_LISTENERS):
            listener(done + it, cost_db)
        if settings.verbose:
            msg = f"iteration {done + it:4d}  cost {cost_db:8.2f} dB  lambda {lam:9.3g}"
            print(msg + (f"  validation {v:8.2f} dB" if validation is not None else ""), flush=True)

    # With settings.stable_at_rest, a start that returns to rest (the
    # linear start of a passive structure) keeps doing so: a step that
    # makes the state equation at rest unstable fails like one whose
    # simulation diverges. Without it, the fit of a joint whose damping
    # grows with the amplitude may push a mode's damping at rest below
    # zero, the branches' higher powers damping it back at the fitted
    # levels: the model then rings by itself under small forces.
    keep_at_rest = settings.stable_at_rest and model.stable_at_rest()

    def admissible_residual(objective, theta):
        trial = model.with_theta(theta)
        if keep_at_rest and not trial.stable_at_rest():
            return None
        return objective.residual(trial)

    theta = model.theta
    for stage, objective in enumerate(objectives):
        n_res = sum(seg.Y.size for seg in objective.segments)
        e0 = objective.residual(model.with_theta(theta))
        if e0 is None:
            raise DivergenceError("the start model diverges on the training data")
        if stage == 0:
            callback(0, theta, float(e0 @ e0), np.nan)
        current = model.with_theta(theta)
        basis = current.step_basis(objective.trajectory(current))
        # BLAS threads as configured here (one thread below a threshold
        # moved EMPS's PNLSS model of the increments from 3.39 to 10.4 mm
        # on its test split by round-off alone: that fit is fragile)
        result = levenberg_marquardt(
            lambda th, obj=objective: admissible_residual(obj, th),
            lambda th, obj=objective: obj.normal_equations(model.with_theta(th)),
            theta, n_drop=model.n_null_directions, max_iter=max_iter, tol=settings.tol, callback=callback,
            basis=basis,
        )
        theta = result.theta
        done += result.n_iter
    if validation is not None:
        # the best on the validation signals first, the start last (kept,
        # as before, when every iterate failed on them)
        order = sorted((it for it in iterates[1:] if np.isfinite(it[2])), key=lambda it: (it[2], it[0]))
        order.append(iterates[0])
    else:
        order = iterates[::-1]
    bounded = {}  # iteration -> its model with its trusted range, each built once

    def bounded_model(iterate):
        if iterate[0] not in bounded:
            bounded[iterate[0]] = trusted_model(model.with_theta(iterate[1]), segments, settings, objective)
        return bounded[iterate[0]]

    def normalised(signals):
        return [start.normalise_inputs(U) for U in signals]

    kept, runaway = _sane_on_new_inputs(order, bounded_model, normalised(settings.new_inputs),
                                        normalised(settings.training_periods), normalised(settings.check_records),
                                        [start.normalise_outputs(Y) for Y in settings.check_outputs])
    return LMFit(
        model=start.with_normalised(bounded_model(kept)),
        n_iter=done, best_iteration=kept[0],
        cost_history=np.array([h[1] for h in result.history]),
        validation_history=np.array([it[2] for it in iterates]) if validation is not None else None,
        validation_error=kept[2] if validation is not None else np.nan,
        kept_cost=kept[3],
        new_input_runaway=runaway,
    )


def _sane_on_new_inputs(order, bounded_model, new_inputs, training_periods=(), check_records=(), check_outputs=()):
    """``(kept, runaway)``: the kept iterate, the first of ``order``
    (``(iteration, theta, validation error, cost)``, most wanted first)
    whose ``bounded_model(iterate)`` does not run away on any of
    ``new_inputs`` (normalised, one period each, dealt to records each
    simulated in turn: see ``runaways_in_turn``) nor on any of
    ``check_records`` (normalised, simulated from rest), and settles into a
    periodic steady state on each of ``training_periods`` (normalised, one
    period each, repeated from rest as a prediction seeks it), and, with
    ``check_outputs`` (normalised, one per check record), simulates each
    check record from rest no worse (rms error) than the earliest iterate
    of ``order``, the fit's start, does; and None when that is the first,
    else :class:`NewInputRunaway`. The first is kept when there are no
    such inputs or no iterate passes.

    The outputs only refuse: an iterate far worse than its start on a
    measured record has jumped to another response or drifted where the
    fit's signals never went (F-16 members on the sine sweeps of the
    estimation levels, missed by several times the output's rms, inside
    the runaway bound), where choosing the best on them would make them
    validation signals.

    The training cost scores each period after a transient of at most a
    period, so a response that drifts away from the fitted orbit by a few
    per cent a period costs it nothing; a prediction repeats the period
    until the state repeats, and then shows the model oscillating by
    itself (an F-16 decoupled model unstable at rest, whose last
    iterations gained little cost and lost the periodic response at a
    fitted level).

    The iterates are probed at 1, 2, 4, ... places down the order, then
    bisected between the last one that failed and the first that passed: a
    few probes rather than every iterate, as a probe that passes simulates
    every input."""
    # each fault the report holds: its field there, the inputs, the places in them a model fails on
    # (for a verdict, as far as the first: the rest need not be simulated)
    runs = {}  # id(model) -> (model, {record: (output, excursion)}): one simulation serves both record checks

    def record_run(model, i):
        done = runs.setdefault(id(model), (model, {}))[1]  # the model held, so that its id is not reused
        if i not in done:
            done[i] = model.simulate_with_excursion(check_records[i])
        return done[i]

    def record_error(model, i):
        Y = record_run(model, i)[0]
        return np.inf if Y is None else float(np.sqrt(np.mean((Y - check_outputs[i]) ** 2)))

    start_errors = [record_error(bounded_model(min(order, key=lambda it: it[0])), i)
                    for i in range(len(check_outputs))]
    checks = (
        ("n_runaway", new_inputs,
         lambda model, inputs, verdict: model.runaways_in_turn(inputs, stop_at_first=verdict)),
        ("runaway_records", check_records,
         lambda model, inputs, verdict: (i for i in range(len(inputs)) if record_run(model, i)[1] > RUNAWAY_FACTOR)),
        ("n_unsettled", training_periods,
         lambda model, inputs, verdict: (i for i, U in enumerate(inputs) if not model.settles(U))),
        ("worse_records", check_outputs,
         lambda model, outputs, verdict: (i for i, e in enumerate(start_errors) if record_error(model, i) > e)),
    )
    if not any(inputs for _, inputs, _ in checks):
        return order[0], None
    first = bounded_model(order[0])
    failing = {name: list(faults(first, inputs, False)) for name, inputs, faults in checks}
    if not any(failing.values()):
        return order[0], None
    report = partial(NewInputRunaway, order[0][0], n_inputs=len(new_inputs), n_training=len(training_periods),
                     n_records=len(check_records), runaway_records=tuple(failing["runaway_records"]),
                     worse_records=tuple(failing["worse_records"]),
                     n_runaway=len(failing["n_runaway"]), n_unsettled=len(failing["n_unsettled"]))
    verdicts = {}

    def passes(k):
        if k not in verdicts:  # the first fault decides: the rest is not simulated
            cand = bounded_model(order[k])
            verdicts[k] = not any(True for _, inputs, faults in checks for _ in faults(cand, inputs, True))
        return verdicts[k]

    failed, last = 0, len(order) - 1
    for probe in [min(2 ** j, last) for j in range(last.bit_length() + 1)]:
        if passes(probe):
            break
        failed = probe
    else:
        return order[0], report(kept_iteration=None)
    while probe - failed > 1:
        middle = (failed + probe) // 2
        failed, probe = (failed, middle) if passes(middle) else (middle, probe)
    return order[probe], report(kept_iteration=order[probe][0])
