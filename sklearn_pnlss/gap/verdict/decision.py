"""Score candidates on validation signals and name the effect behind a gap.

The rules, in order:

1. **Is there a gap?**  The nominal simulation error is tested against the
   noise floor (chi-square with the noise's effective degrees of freedom,
   Bonferroni over signals) and must also exceed it by ``SETTINGS.min_excess_db``
   (``SETTINGS.estimated_floor_min_excess_db`` when the floor is a model's residual):
   otherwise the answer is ``None``.
2. **Closure.**  Each candidate's closure is the fraction of the gap's
   excess over the noise floor, in dB, that it removes on the validation
   signals: ``1 - excess_after_db / excess_before_db`` with ``excess_db =
   10 log10(mse / noise)``, pooled over signals (1: down to the noise,
   0: no better than the nominal).  In dB because gaps span decades: a
   refit that takes a 50 dB excess down to 25 dB has removed 99.7 % of the
   excess power but left a gap far above the noise; it closes 50 %.
3. **Parsimony.**  Candidates within statistical reach of the best closure
   are equivalent; among them refitting the nominal parameters
   (``recalibration``) is preferred to new physics, then fewer parameters.
4. **Explained?**  The chosen candidate must close ``SETTINGS.explained_closure`` of
   the gap.  When the floor is an estimate rather than the data's own
   repetition (a model's residual at the lines the input does not excite,
   the black box's residual), it is also explained by closing as much as
   the black box does (within ``SETTINGS.tie_closure`` and the noise's spread),
   provided the black box closes ``SETTINGS.black_box_min_closure`` itself: then
   every good model stops at the same level, whatever the floor says.  A
   weaker black box is no yardstick (a second mode withheld, one period per
   signal: recalibration closes 67 %, the three-state black box 53 %).
   Otherwise the answer is ``"unexplained"`` (the ranking still shows what
   each candidate achieved, and the black box how much a model without
   physics closes).
5. **What else?**  The combinations fitted by forward selection (a pair,
   then a third effect added to it; see
   :func:`sklearn_pnlss.gap.stages.added_effects`) count when the pair
   closes more than the best single candidate, and each further one more
   than the one before, by the tie and the noise's spread; the verdict
   then names the pair's effect that closes more alone as the main one,
   with the added ones (``added_effects``), explained when the last closes
   ``SETTINGS.explained_closure``.

The noise floor is the training signals' (see
:mod:`sklearn_pnlss.gap.verdict.noise_floor`; its ``source`` is in the decision and the
report).  With no floor at all, closure counts against a floor
``SETTINGS.no_floor_db`` below the nominal gap and no test is made.
"""
from dataclasses import asdict, dataclass, field

import numpy as np

from .noise_floor import gap_test
from ..readings import misfit
from ..settings import SETTINGS

__all__ = ["RankedEffect", "Decision", "decide"]


@dataclass
class RankedEffect:
    """One candidate's result on the validation signals.

    Attributes
    ----------
    name : str
    params : dict
        Fitted physical parameters.
    n_params : int
    gap_before_db, gap_after_db : float
        Validation gap (mean over signals of ``10 log10`` of the mean square
        error) of the nominal simulator and with the effect, dB.
    shrink_db : float
        ``gap_before_db - gap_after_db``.
    closure : float
        Fraction of the gap's excess over the noise floor removed, in dB.
    train_gap_db : float
        Training gap with the effect, dB.
    per_signal_after_db : list of float
    """

    name: str
    params: dict
    n_params: int
    gap_before_db: float
    gap_after_db: float
    shrink_db: float
    closure: float
    train_gap_db: float
    per_signal_after_db: list = field(default_factory=list)

    def __getitem__(self, key):
        return getattr(self, key)

    def to_dict(self):
        d = asdict(self)
        d["params"] = {k: float(v) for k, v in self.params.items()}
        return d


@dataclass(frozen=True)
class Decision:
    """The verdict and the numbers behind it (see the module docstring).
    Frozen: what the report adds to it (the signals left out, the
    recalibration read off the chosen fit) makes a new one."""

    best_effect: object
    significant: bool
    p_value: float
    explained: bool
    ranking: list
    gap_before_db: float
    per_signal_before_db: list
    noise_floor_db: float
    black_box_gap_db: float
    black_box_closure: float
    reason: str
    noise_source: str = None
    noise_detail: str = ""
    sensitive_signals: list = field(default_factory=list)
    recalibrated: dict = field(default_factory=dict)
    main_effect: str = None
    added_effects: list = field(default_factory=list)
    added_names: list = field(default_factory=list)


def _db(x):
    return float(10 * np.log10(max(x, 1e-300)))


def decide(fits, y_meas, y_nominal, y_effects, y_black_box, noise, significance, offsets=False, combinations=(),
           y_combinations=()):
    """Rank candidates and decide; see the module docstring.  With
    ``offsets`` every model is granted each signal's best constant offset
    (see :func:`~sklearn_pnlss.gap.fitting.simulate.misfit`).
    ``combinations`` (EffectFit, each extending the one before) and their
    simulations ``y_combinations`` are the forward selection's."""

    def _mse(measured, simulated):
        return float(np.mean(misfit(simulated, measured, offsets) ** 2))

    before = np.array([_mse(m, s) for m, s in zip(y_meas, y_nominal)])
    sizes = np.array([m.size for m in y_meas])
    noise_var = noise.variance if noise is not None else 0.0
    # Without a noise estimate the floor is unknown: closure is then measured
    # against a floor SETTINGS.no_floor_db below the nominal gap.
    floor = np.full(before.shape, noise_var) if noise is not None else before * 10 ** (-SETTINGS.no_floor_db / 10)
    excess_db = 10 * np.log10(np.maximum(before / floor, 1 + 1e-12))

    def closure(after):
        # Pooled over signals, each weighted by its own excess: a signal the
        # nominal already matches (e.g. a sweep below a saturation level)
        # adds nothing to close, and only counts against a candidate that
        # makes it worse.
        left = 10 * np.log10(np.maximum(after, floor) / floor)
        return float(np.clip(1 - left.sum() / excess_db.sum(), -10.0, 1.0))

    def ranked(fit, ys):
        if ys is None:  # diverged on a validation signal
            after = np.full(before.shape, np.inf)
        else:
            after = np.array([_mse(m, s) for m, s in zip(y_meas, ys)])
        after_db = [_db(a) if np.isfinite(a) else float("inf") for a in after]
        gap_after = float(np.mean(after_db))
        gap_before = float(np.mean([_db(b) for b in before]))
        return RankedEffect(
            name=fit.effect.name, params=dict(fit.physical), n_params=fit.effect.n_params,
            gap_before_db=gap_before, gap_after_db=gap_after, shrink_db=gap_before - gap_after,
            closure=closure(after) if np.all(np.isfinite(after)) else -np.inf,
            train_gap_db=_db(fit.train_mse), per_signal_after_db=after_db,
        )

    ranking = [ranked(fit, ys) for fit, ys in zip(fits, y_effects)]
    order = sorted(range(len(ranking)), key=lambda i: (-ranking[i].closure, ranking[i].n_params))
    ranking = [ranking[i] for i in order]
    fit_by_name = {f.effect.name: f for f in fits}

    bb_gap = bb_closure = float("nan")
    if y_black_box is not None:
        bb_after = np.array([np.inf if s is None else _mse(m, s) for m, s in zip(y_meas, y_black_box)])
        if np.all(np.isfinite(bb_after)):
            bb_gap = float(np.mean([_db(a) for a in bb_after]))
            bb_closure = closure(bb_after)
        else:  # diverged on a validation signal: no yardstick
            bb_gap, bb_closure = float("inf"), -np.inf

    gap_before_db = float(np.mean([_db(b) for b in before]))
    common = dict(ranking=ranking, gap_before_db=gap_before_db,
                  per_signal_before_db=[_db(b) for b in before],
                  noise_floor_db=_db(noise_var) if noise is not None else float("nan"),
                  black_box_gap_db=bb_gap, black_box_closure=bb_closure,
                  noise_source=None if noise is None else noise.source,
                  noise_detail=(f"no noise estimate (no period repeated, no input repeated, no line free "
                                f"of input); closure counted against a floor {SETTINGS.no_floor_db:.0f} dB below "
                                f"the nominal gap") if noise is None else noise.detail)

    if noise is not None:
        p = min(1.0, len(before) * min(gap_test(b, noise, n) for b, n in zip(before, sizes)))
        worst = float(excess_db.max())
        # A floor read from a model's residual is known to about a dB: a
        # gap within that of it is no gap (a null ramp record: the nominal
        # 0.5 dB above its estimated floor, every candidate closing 0 %).
        min_excess = SETTINGS.min_excess_db if noise.replicated else SETTINGS.estimated_floor_min_excess_db
        if p > significance or worst < min_excess:
            return Decision(None, False, p, True, reason=(
                f"no significant gap: the nominal error is {worst:.2f} dB above the noise "
                f"floor (p = {p:.2g})"), **common)
    else:
        p = float("nan")

    best = ranking[0]
    # Statistical reach of a closure: the noise power's spread over the
    # validation samples, relative to the gap's excess.
    spread = 0.0
    if noise is not None:
        nu = np.maximum(noise.dof_per_sample * sizes, 1.0)
        spread = float(np.sum(10 * np.log10(1 + 3 * np.sqrt(2 / nu))) / excess_db.sum())
    equivalent = [r for r in ranking if r.closure >= best.closure - SETTINGS.tie_closure - spread]
    recal = [r for r in equivalent if fit_by_name[r.name].effect.is_recalibration]
    chosen = recal[0] if recal else min(equivalent, key=lambda r: (r.n_params, -r.closure))

    # Forward selection: the pair beats the best single candidate, each
    # further combination the one before, by the tie and the noise's
    # spread; the pair's effect that closes more alone is the main one.
    chain, added = [chosen], []
    for fit, ys in zip(combinations, y_combinations):
        link = ranked(fit, ys)
        if link.closure <= (chain[-1] if len(chain) > 1 else best).closure + SETTINGS.tie_closure + spread:
            break
        parts = link.name.split(" + ")
        if len(chain) == 1:
            chain = [max((r for r in ranking if r.name in parts), key=lambda r: r.closure)]
            added = [p for p in parts if p != chain[0].name]
        else:
            added.append(parts[-1])
        chain.append(link)
    chosen = chain[0]
    last = chain[-1]
    # The black box as yardstick where the floor is only an estimate: a
    # candidate that closes as much as a good model without physics has
    # closed what a model can, wherever the estimate put the floor.
    estimated_floor = noise is None or not noise.replicated
    as_black_box = bool(estimated_floor and np.isfinite(bb_closure) and bb_closure >= SETTINGS.black_box_min_closure
                        and last.closure >= bb_closure - SETTINGS.tie_closure - spread)
    explained = last.closure >= SETTINGS.explained_closure or as_black_box
    if explained:
        name = chosen.name
        reason = (f"{chosen.name} closes {percent(chosen.closure)} of the gap "
                  f"({chosen.gap_before_db:.1f} -> {chosen.gap_after_db:.1f} dB)")
        if len(chain) > 1:
            reason += (f"; with {', '.join(added)} added, {percent(last.closure)} "
                       f"({last.gap_after_db:.1f} dB)")
        if last.closure < SETTINGS.explained_closure:
            reason += f", as much as the black box ({percent(bb_closure)})"
        if len(equivalent) > 1 and len(chain) == 1:
            others = ", ".join(r.name for r in equivalent if r is not chosen)
            reason += f"; as good within the noise: {others} (more parameters or new physics)"
    else:
        name = "unexplained"
        reason = f"the best candidate, {best.name}, closes only {percent(best.closure)} of the gap"
        if len(chain) > 1:
            reason += f"; {chosen.name} with {', '.join(added)} added, {percent(last.closure)}"
        if np.isfinite(bb_closure):
            reason += f"; the black box closes {percent(bb_closure)}"
        elif y_black_box is not None:
            reason += "; the black box diverged"
        if noise is None:
            # Say why a closure may fall short: the floor is a guess.
            reason += f" (no noise floor: closure counted against a floor {SETTINGS.no_floor_db:.0f} dB below the gap)"
    return Decision(name, True, p, explained, reason=reason, main_effect=chosen.name,
                    added_effects=chain[1:], added_names=added, **common)


def percent(fraction):
    """A closure as a whole percentage, never ``-0 %``; ``diverged`` for a
    simulation that diverged (closure minus infinity)."""
    if not np.isfinite(fraction):
        return "diverged" if fraction < 0 else "n/a"
    value = round(100 * fraction)
    return f"{value:d} %"
