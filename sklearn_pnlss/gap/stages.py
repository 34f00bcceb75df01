"""The stages of a gap diagnosis' fit, in the order :data:`STAGES` runs them.

Each stage reads and updates one :class:`Fitting` (the training data as
fitted, the candidates, their fits so far) and says in its docstring what it
does and why; the thresholds it compares with are in
:mod:`sklearn_pnlss.gap.settings`.

1. :func:`measurement_chain`: the nominal's own errors first (its refit,
   and a delay between the channels with it); a delay found there is the
   measurement chain's and is fitted with every candidate.
2. :func:`all_candidates`: every other candidate at the fitting rate, and
   the black box.
3. :func:`refine_contenders`: the candidates still in contention refined at
   the reporting rate.
4. :func:`hidden_delay`: a channel delay looked for again behind the best
   candidate.
5. :func:`polish_leader`: the best candidate's fit carried on while it
   still improves.
6. :func:`added_effects`: a second and third effect added to the best one
   while it leaves a gap.
7. :func:`information`: what the training data say about each final fit's
   parameters, for the report's covariance.
"""
import itertools
from dataclasses import dataclass, field, replace

import numpy as np
from joblib import Parallel, delayed
from scipy.stats import chi2

from .candidates.clues import read_clues
from .candidates.effects import InputDelay, delay_signal
from .fitting.black_box import fit_black_box
from .fitting.calibrate import at_rate, fit_effect, parameter_information, pooled_mse, refine_fit, signal_errors
from .results import ChannelDelay
from .settings import SETTINGS
from ..utils.threads import one_blas_thread

__all__ = ["Fitting", "STAGES", "measurement_chain", "all_candidates", "refine_contenders", "hidden_delay",
           "polish_leader", "added_effects", "information"]

BLACK_BOX = "__black_box__"


def _expected_cost(name, task):
    """Rough relative cost of a task, to start the long ones first: the
    starts times the parameters (each iteration simulates once per
    parameter); the black box counts as a mid-sized candidate."""
    if name == BLACK_BOX:
        return 8
    first = task[1][0]  # a fit task's effect, or a refinement's fit
    effect = getattr(first, "effect", first)
    return len(effect.starts) * max(effect.n_params, 1)


@dataclass
class Fitting:
    """What the stages of one diagnosis' fit share.

    Attributes
    ----------
    diagnosis : GapDiagnosis
        The estimator being fitted: its parameters, ``scales_``, ``noise_``
        and ``train_gap_db_``.
    u_list, y_list, y_centred : list of ndarray
        Training inputs, measured outputs, and the outputs less their
        offsets (the black box and the clues read those).
    train, coarse : SignalSet
        The training inputs at the reporting rate and at the fitting rate.
    clues : DataClues
        The training data's readings that start the candidates.
    raw : list of Effect
        The candidates as listed (the effect alone).
    recalibration : Recalibration or None
        The nominal's refit every candidate is fitted with (None: the
        nominal is exact).
    effects : list of Effect
        The candidates as they are fitted now: each with the nominal's
        refit, and a found delay.
    settings : dict
        ``fit_effect``'s keywords shared by every fit (``ftol``,
        ``offsets``, ``noise_variance``).
    done : dict
        Name -> EffectFit (the black box: its model) of each fit so far.
    delay : dict or None
        The channel delay found, once found.
    measured : list of Effect
        The measurement chain's candidates (the nominal's refit, the delay).
    """

    diagnosis: object
    u_list: list
    y_list: list
    y_centred: list
    y_nominal: list
    train: object
    coarse: object
    clues: object
    raw: list
    recalibration: object
    settings: dict
    effects: list = None
    done: dict = field(default_factory=dict)
    delay: dict = None
    measured: list = field(default_factory=list)
    combinations: list = field(default_factory=list)
    _finished: object = field(default_factory=lambda: itertools.count(1))
    _fitted: set = field(default_factory=set)
    _planned: set = field(default_factory=set)
    _n_tasks: int = 0

    def __post_init__(self):
        self.effects = [self.composed(e) for e in self.raw]
        self._planned = {e.name for e in self.effects} | ({BLACK_BOX} if self.diagnosis.black_box else set())
        self._n_tasks = len(self._planned)

    def composed(self, effect):
        """``effect`` (as listed, or several together) as every candidate
        is fitted: with the nominal's refit, and the channel delay once
        found."""
        if self.recalibration is None:
            return effect
        if effect.is_recalibration:
            return self.recalibration
        effect = effect.with_recalibration(self.recalibration)
        return effect if self.delay is None else effect.with_delay(InputDelay(), self.delay.samples)

    # -- tasks -----------------------------------------------------------------
    def fit_task(self, effect, clues=None, max_nfev=None, full_rate=False, refine=True, signal=None):
        """A fit of ``effect``: at the fitting rate and refined at the
        reporting rate; ``full_rate``: at the reporting rate only (carrying
        on a fit refined there already); ``refine=False``: at the fitting
        rate only (see :func:`refine_contenders`); ``signal``: on that
        training signal alone, at the fitting rate (see :func:`_raced`)."""
        d = self.diagnosis
        signals, y_list = self.train if full_rate else self.coarse, self.y_list
        if signal is not None:
            signals, y_list, refine = signals.subset([signal]), [y_list[signal]], False
        return delayed(fit_effect)(effect, d.nominal, d.scales_, signals, y_list,
                                   max_nfev=d.max_nfev if max_nfev is None else max_nfev,
                                   fine_signals=self.train if refine and not full_rate else None,
                                   clues=self.clues if clues is None else clues, **self.settings)

    def refine_task(self, fit):
        """``fit`` (made at the fitting rate) carried on to the reporting rate."""
        d = self.diagnosis
        return delayed(refine_fit)(fit, d.nominal, d.scales_, self.coarse, self.y_list, fine_signals=self.train,
                                   clues=self.clues, max_nfev=d.max_nfev, **self.settings)

    def black_box_task(self):
        d = self.diagnosis
        return delayed(fit_black_box)(self.u_list, self.y_centred, d.period, d.random_state, 1)

    def run(self, tasks):
        """Run ``tasks`` (name -> task) in one pool, the costliest started
        first so that the last to finish is a short one; their results by
        name."""
        # a refit, or a task not planned at the start (a combination), adds to the count
        self._n_tasks += sum(name in self._fitted or name not in self._planned for name in tasks)
        self._fitted.update(tasks)
        self._planned.update(tasks)
        order = sorted(tasks, key=lambda name: -_expected_cost(name, tasks[name]))
        with one_blas_thread():
            return dict(zip(order, Parallel(n_jobs=self.diagnosis.n_jobs, prefer="threads")(
                delayed(self._announced)(k, tasks[k]) for k in order)))

    def _announced(self, name, task):
        # Each candidate says when it is done (from its worker thread): the
        # progress of a fit that takes minutes.
        func, args, kwargs = task
        out = func(*args, **kwargs)
        if self.diagnosis.verbose:
            what = "the black box" if name == BLACK_BOX else (
                f"{name}: training {10 * np.log10(out.train_mse):.2f} dB, {out.n_evaluations} "
                f"simulations, {out.seconds:.1f} s")
            self.log(f"{next(self._finished)}/{self._n_tasks} done, {what}")
        return out

    def log(self, text):
        self.diagnosis._log(text)

    # -- readings ---------------------------------------------------------------
    def on_every_signal(self, fit):
        """``fit`` (made on some of the training signals, at the fitting
        rate) with its errors taken on all of them (one simulation)."""
        d = self.diagnosis
        mse = at_rate(fit, d.nominal, d.scales_, self.coarse, self.y_list, d.offsets).coarse_mse
        return replace(fit, train_mse=mse, coarse_mse=mse)

    def signal_errors(self, fit):
        """Mean squared error of ``fit`` on each training signal at the
        fitting rate (one simulation)."""
        d = self.diagnosis
        return signal_errors(fit, d.nominal, d.scales_, self.coarse, self.y_list, d.offsets)

    def most_telling_signal(self, errors):
        """The training signal with the most error in it (``errors``: a
        fit's :meth:`signal_errors`): the one that tells most about what
        that fit leaves to explain."""
        return int(np.argmax(errors * [y.size for y in self.y_list]))

    def aligned_clues(self, delay_s):
        """The clues as the delayed model sees the data: the input (and the
        nominal's response, time-invariant) delayed by the channel delay;
        read off the raw channels, a delay of a millisecond is a phase error
        larger than a second mode's whole change."""
        d, train = self.diagnosis, self.train
        periodic = [bool(P) for P in train.n_periods]
        shift = delay_s * d.fs
        return read_clues(d.nominal, [delay_signal(u, shift, p) for u, p in zip(self.u_list, periodic)],
                          self.y_centred, [delay_signal(y, shift, p) for y, p in zip(self.y_nominal, periodic)],
                          train.n_periods, d.period_, d.fs)

    def nested_fits(self):
        """The fits that every candidate contains: the nominal's refit
        (``recalibration``, when the nominal is freed), and the refit with
        the channel delay once one is found (every candidate is then fitted
        with it)."""
        if not self.diagnosis._free_nominal():
            return []
        return [self.done[e.name] for e in self.effects if e.name in self.done
                and (e.is_recalibration or (self.delay is not None and e.name == "input_delay"))]

    def nominal_excess_db(self):
        """The nominal's training error over the noise floor, dB (0 without
        a floor): the scale the verdict's tie is a share of."""
        d = self.diagnosis
        return 0.0 if d.noise_ is None else d.train_gap_db_ - 10 * np.log10(d.noise_.variance)

    def adds_to(self, fit, nested):
        """Whether ``fit`` explains more of the training data than
        ``nested``, the fit it contains, by what the verdict could tell on
        validation: its cost lower by more than the chi-square quantile of
        its extra parameters at the diagnosis' ``significance``, in units of
        the noise (an F-test with the noise known), and its error lower by
        more than ``tie_closure`` of the nominal's excess over the noise, in
        dB (the verdict's own tie; far above the noise the first test
        passes for any extra parameter).  A candidate that does not cannot
        beat the nominal's refit, which the verdict prefers whenever it
        explains as much.  Without a nested fit or a noise floor, every
        candidate adds."""
        d = self.diagnosis
        if nested is None or d.noise_ is None or fit is nested:
            return True
        n_samples = sum(y.size for y in self.y_list)
        extra = max(fit.effect.n_params - nested.effect.n_params, 1)
        gain = (nested.coarse_mse - fit.coarse_mse) * n_samples * d.noise_.dof_per_sample / d.noise_.variance
        excess_db = self.nominal_excess_db()
        gain_db = 10 * np.log10(nested.coarse_mse / fit.coarse_mse)
        return bool(gain > chi2.ppf(1 - d.significance, extra) and gain_db > SETTINGS.tie_closure * excess_db)


# -- the stages -------------------------------------------------------------------
def measurement_chain(run):
    """Fit the nominal's own errors first: ``recalibration``, and a delay
    between the force and displacement channels with it (when both are
    candidates and the nominal is freed: they are then nested, the delay at
    zero is the recalibration).

    A delay that improves the refit by ``delay_found_db`` is a property of
    the measurement chain (a sensor, an anti-alias filter): every other
    candidate is fitted with it free too, and the clues are read at it.
    Every other candidate contains the nominal's refit, so the fitting rate
    is corrected by that refit's own discretisation error (corrected by the
    nominal's, a stiffness 5 % off left every candidate 7 dB above the
    noise); the two fits are scored at that rate too.
    """
    d = run.diagnosis
    by_name = {e.name: e for e in run.effects}
    if not d._free_nominal() or "recalibration" not in by_name or "input_delay" not in by_name:
        return
    run.measured = [by_name["recalibration"], by_name["input_delay"]]
    run.done = run.run({e.name: run.fit_task(e) for e in run.measured})
    recal, delay = run.done["recalibration"], run.done["input_delay"]
    gain_db = 10 * np.log10(recal.train_mse / delay.train_mse)
    if gain_db >= SETTINGS.delay_found_db:
        run.delay = ChannelDelay(float(delay.physical["delay_s"]), float(delay.theta[0]), float(gain_db),
                                 "recalibration")
        run.log(f"the data carry a delay of {1e3 * run.delay.delay_s:.3g} ms "
                f"({run.delay.gain_db:.1f} dB better fit); it is fitted with every candidate")
        run.clues = run.aligned_clues(run.delay.delay_s)
        run.effects = [e if e.name in run.done else e.with_delay(InputDelay(), run.delay.samples) for e in run.effects]
        _recalibration_with_delay(run)
    refit = min(run.nested_fits(), key=lambda f: f.train_mse)
    run.coarse = run.train.coarse(d.fit_oversampling, *refit.effect.simulator(refit.theta, d.nominal, d.scales_)[:2])
    run.done = {name: at_rate(fit, d.nominal, d.scales_, run.coarse, run.y_list, d.offsets)
                for name, fit in run.done.items()}


def _recalibration_with_delay(run):
    """The candidates once the first look has found a channel delay.

    The delay is the measurement chain's, so the nominal's own error is
    the refit *with* it: when that refit moved a nominal parameter by
    ``recalibration_shown`` or more, it becomes ``recalibration`` (the
    verdict names the parameters and the channel delay) and
    ``input_delay`` leaves the candidates: a stiffness 5 % off seen
    through a sensor's delay is a recalibration, not a delay with a side
    note.  The refit without the delay, left far above the noise, is no
    candidate any more.  When nothing moved, the delay alone explains the
    nominal's error and is reported as ``input_delay``.
    """
    refit = run.done["input_delay"]
    if all(abs(v) < SETTINGS.recalibration_shown for v in run.diagnosis._nominal_moves(refit).values()):
        return
    recal = next(e for e in run.effects if e.is_recalibration)
    relabelled = refit.effect.variant(name=recal.name, is_recalibration=True,
                                      description=recal.description + ", with the channels' delay")
    run.done[recal.name] = replace(refit, effect=relabelled)
    del run.done["input_delay"]
    run.effects = [relabelled if e.is_recalibration else e for e in run.effects if e.name != "input_delay"]


def all_candidates(run):
    """Fit every candidate not fitted yet at the fitting rate (and the
    black box, which needs no rate), all in one pool."""
    tasks = {e.name: run.fit_task(e, refine=False) for e in run.effects if e.name not in run.done}
    if run.diagnosis.black_box:
        tasks[BLACK_BOX] = run.black_box_task()
    run.done.update(run.run(tasks))


def refine_contenders(run):
    """Refine at the reporting rate the candidates still in contention:
    those whose training error at the fitting rate is within
    ``contention_db`` of the best one's and that add to the nominal's refit
    they contain (:meth:`Fitting.adds_to`).

    The verdict compares the best candidates, and their parameters must
    hold at the rate every validation simulation runs at; a candidate ten
    times worse on training cannot become the best on validation, and
    refining it (the model's own discretisation error carried over, a
    check at the reporting rate, sometimes a whole fit there) was half of
    its time: on the clean cubic case, a fit of the wrong hysteresis at the
    reporting rate cost 99 of a diagnosis' 150 s.
    """
    done = run.done
    fitted = [e for e in run.effects if e.name in done and done[e.name].effect.n_params]
    if not fitted:
        return
    best = min(done[e.name].coarse_mse for e in fitted)
    nested = min(run.nested_fits(), key=lambda f: f.coarse_mse, default=None)
    contenders = [e.name for e in fitted if done[e.name].coarse_mse <= best * 10 ** (SETTINGS.contention_db / 10)
                  and not done[e.name].refined and run.adds_to(done[e.name], nested)]
    done.update(run.run({name: run.refine_task(done[name]) for name in contenders}))


def hidden_delay(run):
    """Look for a channel delay behind a dominant nonlinearity, when the
    first look found none.

    With a strong nonlinear effect the nominal refit leaves an error the
    delay barely changes (a backlash at -59 dB hides a delay worth
    -70 dB), so the first look misses it.  The delay is looked for again
    on the best refined candidate: if freeing it gains ``hidden_delay_db``
    there (probed on the training signal that candidate misfits most, then
    confirmed on all), it belongs to the measurement chain and every
    candidate is refitted with it at the fitting rate, from its own fit and
    from its clues aligned at that delay (with half the iterations: most of them
    start close; raced as the forward selection's pairs, see
    :func:`_raced`), and those in contention are refined as after the first
    fits (:func:`refine_contenders`; refining every one cost family d's
    stiff backlash 18 s of its 148 s of CPU).  Skipped
    when the best candidate already sits within ``hidden_delay_db`` of the
    noise floor: no delay could gain that.
    """
    d, done = run.diagnosis, run.done
    if not run.measured or run.delay is not None:
        return
    measured = {e.name for e in run.measured}
    rest = [e for e in run.effects if e.name not in measured]
    contenders = [e for e in rest if done[e.name].refined]
    if not contenders:
        return  # no candidate adds to the nominal's refit: no nonlinearity to hide a delay
    best = min(contenders, key=lambda e: done[e.name].train_mse)
    if d.noise_ is not None and done[best.name].train_mse < d.noise_.variance * 10 ** (SETTINGS.hidden_delay_db / 10):
        return
    delay_start = done["input_delay"].theta[:1]  # its theta: the delay's (samples), then the refitted nominal's

    def delayed_effect(e, starts=()):
        # from its fit without the delay (whose listed starts were tried
        # then: the warm start holds the best of them)
        warm = np.append(done[e.name].theta, delay_start)
        return e.with_delay(InputDelay(), delay_start).variant(starts=[warm] + list(starts), data_starts=[])

    clues_at = {}  # the clues aligned at each delay (samples), read once for every candidate

    def aligned_starts(e, shifts):
        # e's data starts from the clues aligned at each delay
        starts = []
        for shift in shifts:
            if shift not in clues_at:
                clues_at[shift] = run.aligned_clues(shift / d.fs)
            starts += e.with_delay(InputDelay(), [shift]).data_starts(clues_at[shift], d.nominal, d.scales_)
        return starts

    # The first look's delay is biased by the nonlinearity it could not
    # fit: the best candidate's clues are read at several delays (a start
    # costs one simulation), on the training signal it leaves the most
    # error in (a quarter of the simulations with four signals: a delay
    # that gains nothing there gains nothing on all of them).
    shifts = sorted({round(float(delay_start[0]), 3), *SETTINGS.hidden_delay_shifts})
    errors = run.signal_errors(done[best.name])
    signal = run.most_telling_signal(errors)
    probe = run.run({best.name: run.fit_task(delayed_effect(best, aligned_starts(best, shifts)),
                                             signal=signal)})[best.name]
    if 10 * np.log10(errors[signal] / probe.coarse_mse) < SETTINGS.hidden_delay_db:
        return
    trial = run.run({best.name: run.fit_task(delayed_effect(best, [probe.theta]))})[best.name]
    gain_db = 10 * np.log10(done[best.name].train_mse / trial.train_mse)
    if gain_db < SETTINGS.hidden_delay_db:
        return
    run.delay = ChannelDelay(float(trial.physical["delay_s"]), float(trial.theta[-1]), float(gain_db), best.name)
    run.log(f"the data carry a delay of {1e3 * run.delay.delay_s:.3g} ms, hidden behind {best.name} "
            f"({gain_db:.1f} dB better fit with it); every candidate is refitted with it")
    found = [run.delay.samples]
    refits = {e.name: delayed_effect(e, aligned_starts(e, found)) for e in rest if e is not best}
    done[best.name] = trial
    done.update(_raced(run, refits, max(3, d.max_nfev // 2), run.most_telling_signal(run.signal_errors(trial))))
    # the effects as refitted, the delay free in each
    run.effects = [e if e.name in measured else done[e.name].effect for e in run.effects]
    refine_contenders(run)  # as after the first fits: the others cannot lead


def polish_leader(run):
    """Carry on the fit of the refined candidate with the lowest training
    error while it stops on its iteration budget and still improves.

    The verdict rests on that candidate, and a needle-narrow minimum (a
    stiff backlash with a channel delay and the nominal refitted: six
    parameters, 0.1 % wide) can take more iterations than the budget every
    other candidate gets.  At most ``leader_budgets`` more budgets, each at
    the reporting rate from where the last stopped, and only while a budget
    gains what the verdict could see (:func:`_budget_worth_db`) and the
    training error is ``leader_progress_db`` above the noise floor (where
    the data give one before the fits): a fit at the noise has nothing
    left to gain.  A budget is granted only when the fit's own progress
    over the last half of its evaluations, carried over a budget, promises
    that gain: a fit crawling far above the noise (a hysteresis standing in
    for a backlash it cannot fit, 0.04 dB per evaluation) gains less than
    the verdict's tie in a budget of 11 s.
    """
    done = run.done
    leader = min((e for e in run.effects if done[e.name].effect.n_params and done[e.name].refined),
                 key=lambda e: done[e.name].train_mse, default=None)
    if leader is not None:
        done[leader.name] = _carried_on(run, done[leader.name])


def _budget_worth_db(run):
    """The training gain (dB) a further budget must bring: at least
    ``leader_progress_db``, and the verdict's tie (``tie_closure`` of the
    nominal's excess over the noise, dB), below which no closure it
    compares moves."""
    return max(SETTINGS.leader_progress_db, SETTINGS.tie_closure * run.nominal_excess_db())


def _carried_on(run, fit):
    """``fit`` carried on at the reporting rate, a budget at a time, while
    it stops on its budget, promises and gains :func:`_budget_worth_db`,
    and stays ``leader_progress_db`` above the noise floor
    (``leader_budgets`` at most; see :func:`polish_leader`)."""
    d = run.diagnosis
    floor = 0.0 if d.noise_ is None else d.noise_.variance * 10 ** (SETTINGS.leader_progress_db / 10)
    worth_db, name = _budget_worth_db(run), fit.effect.name
    for _ in range(SETTINGS.leader_budgets):
        if fit.converged or fit.train_mse < floor or fit.progress_db * d.max_nfev < worth_db:
            break
        warm = fit.effect.variant(starts=[fit.theta], data_starts=[])
        more = run.run({name: run.fit_task(warm, full_rate=True)})[name]
        gain_db = 10 * np.log10(fit.train_mse / more.train_mse)
        if gain_db <= 0:
            break
        fit = replace(more, n_evaluations=fit.n_evaluations + more.n_evaluations, seconds=fit.seconds + more.seconds)
        run.log(f"{name} carried on: training {10 * np.log10(more.train_mse):.2f} dB ({gain_db:.1f} dB better)")
        if gain_db < worth_db:
            break
    return fit


def added_effects(run):
    """Forward selection: a second (and a third) effect added while the best
    one leaves a gap.

    Real structures seldom miss exactly one effect.  When the refined
    candidate with the lowest training error closes less than
    ``explained_closure`` of the nominal's training excess over the noise,
    pairs are fitted: each of the ``forward_bases`` best refined candidates
    with every other physical effect (at the fitting rate, half the
    iteration budget, from both fits).  The best candidate alone can be the
    wrong one, a flexible effect standing in for two others (a hysteresis
    closing 56 % of a cubic spring with quadratic damping, where the cubic
    spring alone closes 26 %), so the pairs do not all start from it.  The
    best pair that adds to the best single fit (:meth:`Fitting.adds_to`) is
    refined (and carried on as :func:`polish_leader` does), and a third
    effect is looked for the same way from it, at most
    ``max_added_effects`` in all.  The combinations are kept in
    ``run.combinations``; whether each pays is decided on validation (see
    :func:`~sklearn_pnlss.gap.verdict.decision.decide`).  Needs a noise
    floor from the data to judge the gap left.
    """
    d, done = run.diagnosis, run.done
    if d.noise_ is None:
        return
    physical = {e.name: e for e in run.raw if not e.is_recalibration and e.name != "input_delay" and e.name in done}
    refined = sorted((done[name] for name in physical if done[name].refined), key=lambda f: f.train_mse)
    if not refined:
        return
    leader, bases = refined[0], [(physical[f.effect.name], f) for f in refined[:SETTINGS.forward_bases]]
    nominal_excess_db = run.nominal_excess_db()
    for _ in range(SETTINGS.max_added_effects):
        left_db = 10 * np.log10(max(leader.train_mse / d.noise_.variance, 1.0))
        if nominal_excess_db <= 0 or 1 - left_db / nominal_excess_db >= SETTINGS.explained_closure:
            return
        pairs, raws, planned = {}, {}, set()
        for raw_base, base in bases:
            for other in physical.values():
                together = frozenset([*raw_base.parts, other.name])
                if other.name in raw_base.parts or together in planned:
                    continue  # in the base already, or this set of effects is planned from another base
                planned.add(together)
                raw = raw_base.plus(other)
                pair = run.composed(raw).variant(starts=_pair_starts(raw_base, base, other, done[other.name]),
                                                 data_starts=[])
                pairs[raw.name] = pair
                raws[raw.name] = raw
        if not pairs:
            return
        budget, errors = max(3, d.max_nfev // 2), run.signal_errors(leader)
        fitted = _raced(run, pairs, budget, run.most_telling_signal(errors))
        best = min(fitted, key=lambda name: fitted[name].coarse_mse)
        if not run.adds_to(fitted[best], _reach(run, leader, errors, budget)):
            return
        # refined, and carried on like the leading candidate: the verdict may rest on it
        refined_best = _carried_on(run, run.run({best: run.refine_task(fitted[best])})[best])
        run.log(f"{best}: training {10 * np.log10(refined_best.train_mse):.2f} dB "
                f"(the best alone {10 * np.log10(leader.train_mse):.2f} dB)")
        run.combinations.append(refined_best)
        leader, bases = refined_best, [(raws[best], refined_best)]


def _reach(run, fit, errors, budget):
    """``fit`` as a pair fitted from it is compared with: its error at the
    fitting rate at its parameters now (``errors``: its
    :meth:`Fitting.signal_errors`), less what its own progress
    (``progress_db``) promises over the pair's ``budget``.  Its
    ``coarse_mse`` is that of its first fit, before it was refined: a pair
    with more iterations than that beat it by iterations alone (a
    hysteresis with an input saturation, 0.03 dB better on training,
    then a third effect looked for: 41 s).  Both at the fitting rate."""
    now = pooled_mse(errors, run.y_list)
    return replace(fit, coarse_mse=now * 10 ** (-fit.progress_db * budget / 10))


def _raced(run, effects, budget, signal):
    """Fits of ``effects`` (name -> Effect) at the fitting rate within
    ``budget`` iterations, raced: every one gets ``SETTINGS.race_iterations``
    on the training ``signal`` alone first (the one the fit they extend
    leaves the most error in: a quarter of the simulations with four
    signals), and only the ``SETTINGS.race_survivors`` best then carry on,
    on every signal, from where they stopped, for the rest of the budget.
    The others keep their short fits, far behind, their errors taken on
    every signal: the forward selection's pairs and the refits behind a
    hidden delay are a dozen or more fits each, of which one or two
    matter."""
    first = min(SETTINGS.race_iterations, budget)
    fitted = run.run({name: run.fit_task(e, max_nfev=first, signal=signal) for name, e in effects.items()})
    ahead = sorted(fitted, key=lambda name: fitted[name].coarse_mse)[:SETTINGS.race_survivors]
    rest = {name: run.fit_task(fitted[name].effect.variant(starts=[fitted[name].theta], data_starts=[]),
                               max_nfev=max(budget - first, 1), refine=False) for name in ahead}
    fitted.update(run.run(rest))
    return {name: fit if name in rest else run.on_every_signal(fit) for name, fit in fitted.items()}


def _pair_starts(raw_base, base, other, other_fit):
    """Starts of ``raw_base`` plus ``other`` (their ``theta`` in turn, then
    the nominal's refit and delay): the base's fit with the other's own fit
    (its effect's part) or its first listed start, the nominal's refit and
    delay as the base has them."""
    n_base, n_other = raw_base.bounds[0].size, other.bounds[0].size
    rest = base.theta[n_base:]
    return [np.concatenate([base.theta[:n_base], s, rest]) for s in (other_fit.theta[:n_other], other.starts[0])]


def information(run):
    """Every final fit's information on the training signals (one Jacobian
    each, in parallel; see
    :func:`~sklearn_pnlss.gap.fitting.calibrate.parameter_information`),
    so that the report's parameter covariance reads it instead of fitting
    again."""
    d = run.diagnosis
    fits = [f for name, f in run.done.items() if name != BLACK_BOX and f.effect.n_params] + run.combinations
    with one_blas_thread():
        found = Parallel(n_jobs=d.n_jobs, prefer="threads")(
            delayed(parameter_information)(f, d.nominal, d.scales_, run.coarse, run.y_list, d.offsets) for f in fits)
    for f, info in zip(fits, found):
        f.information = info


#: The stages of :meth:`GapDiagnosis.fit`, in order.
STAGES = (measurement_chain, all_candidates, refine_contenders, hidden_delay, polish_leader, added_effects,
          information)
