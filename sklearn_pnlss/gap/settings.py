"""Every threshold of the gap diagnosis, in one place, with what set it.

The diagnosis makes a handful of yes/no decisions (is there a gap, did a
delay show, which candidates are still in contention, is a fit stalled on a
needle, does a candidate explain the gap); each compares a measured figure
with one of the values below.  They are grouped by the stage that reads
them (see :data:`sklearn_pnlss.gap.diagnosis.STAGES`), and each says why it
has its value: a statistical argument, or the measurement that set it.
Numerical resolutions that decide nothing (grid sizes, FFT segment lengths,
integration tolerances) stay beside the code that uses them.
"""
from dataclasses import dataclass

__all__ = ["GapSettings", "SETTINGS"]


@dataclass(frozen=True)
class GapSettings:
    """The thresholds of a gap diagnosis (see the module's docstring)."""

    # -- the data ---------------------------------------------------------------
    #: A line carries no input when its power is this far below the strongest
    #: line of the record (or segment) it is read in, dB.
    non_excited_db: float = -60.0
    #: Two inputs are the same realisation when they differ by less than this
    #: (relative power, dB): a shaker driven twice by one signal measures two
    #: nearly equal forces.
    same_input_db: float = -60.0
    #: A signal whose periods differ by this much more (power ratio) than the
    #: quietest other signal's periods do has not settled.  Realisations
    #: measured by one sensor differ in that spread by chance alone by about
    #: 1 dB (four periods, thousands of lines); a chaotic response by tens of dB.
    unsettled_ratio: float = 10.0
    #: Share of the nominal's start-up transient found in a signal's misfit
    #: above which ``period=None`` is warned about: three standard deviations
    #: of a chance projection on a short record.
    steady_state_share: float = 0.3

    # -- the measurement chain's delay ---------------------------------------------
    #: Training improvement (dB) of the nominal refit with a channel delay over
    #: the refit alone above which the delay is fitted with every candidate.
    delay_found_db: float = 1.0
    #: Training improvement (dB) of the best candidate with a channel delay over
    #: it alone above which a delay the first look missed is taken as found.
    #: Higher than ``delay_found_db``: a candidate that does not fit the data
    #: also gains from any extra parameter (measured: 2-3 dB from a spurious
    #: delay on a backlash it does not explain), while a delay hidden behind
    #: the right effect is worth tens of dB once both are fitted.
    hidden_delay_db: float = 6.0
    #: Channel delays, samples, at which the clues of a candidate are read when
    #: a delay may hide behind it (the first look's delay is biased by the
    #: nonlinearity it could not fit).
    hidden_delay_shifts: tuple = (0.5, 1.0, 1.5, 2.0, 3.0)
    #: Smallest relative change of a freed nominal parameter the verdict
    #: names; a delay found with a refit that moves one this much is a
    #: recalibration seen through the sensor's delay.
    recalibration_shown: float = 0.005

    # -- fitting a candidate -----------------------------------------------------------
    #: Data starts kept (the best on the first training signal) for a full
    #: evaluation when an effect lists more: a profile gives dozens, each a
    #: simulation of every signal, and on one signal they rank alike.
    screened_starts: int = 4
    #: Data starts (the best at the fitting rate) tried again at the reporting rate.
    fine_data_starts: int = 3
    #: Training error at the reporting rate over the defect-corrected coarse
    #: one above which the fit is refitted at the reporting rate (3 dB).
    fine_mismatch: float = 2.0
    #: Defect corrections at most, each carrying the model's discretisation
    #: error at the latest estimate (one left a cubic spring at 1e8 N/m^3 4
    #: standard errors off in damping; the second lands on the fine optimum).
    defect_rounds: int = 3
    #: A training signal whose misfit is this many times the median signal's
    #: (10 dB) has jumped to another steady state; one whose sensitivity is
    #: that many times makes the misfit a needle.
    jump_ratio: float = 10.0
    #: A fit that stops on its budget within this many dB of the noise is
    #: looked at for a needle signal (looking at every stopped fit doubled a
    #: clean stiff backlash's time, 152 -> 304 s, for nothing).
    needle_reach_db: float = 10.0

    # -- which candidates are refined ----------------------------------------------------
    #: Candidates whose training error at the fitting rate is within this many
    #: dB of the best one's are refined at the reporting rate; the others keep
    #: their coarse fit (a candidate ten times worse on training cannot become
    #: the best on validation; refining the wrong hysteresis on the clean
    #: cubic case cost 99 of a diagnosis' 150 s).
    contention_db: float = 10.0
    #: Further budgets of ``max_nfev`` iterations the leading candidate gets
    #: when its fit stops on the budget while still improving (measured on the
    #: stiff backlash of family d, seed 101: the budget ran out at -97.0 dB of
    #: training error, 0.4 % off in mass and stiffness, the noise at -103 dB).
    leader_budgets: int = 2
    #: Training improvement (dB) a further budget must promise (the fit's
    #: progress over its last evaluations, carried over a budget) and bring,
    #: at least (the verdict's tie raises it far above the noise), and the
    #: leader's distance to the noise floor below which it gets none
    #: (carrying on fits at the noise cost the other cases a third more time).
    leader_progress_db: float = 0.5

    #: Effects added at most to the best one while it leaves a gap (forward
    #: selection: a second, then a third).
    max_added_effects: int = 2
    #: Best single candidates each paired with every other effect when the
    #: best leaves a gap: the best alone can stand in for two others (a
    #: hysteresis for a cubic spring with quadratic damping: 56 % closed,
    #: the cubic spring alone 26 %).  Every pair is fitted: ranked by its
    #: start (the two single fits side by side) the hysteresis' pairs came
    #: first and the right one was lost (family t, both seeds).
    forward_bases: int = 3
    #: The pairs (and triples) are raced: each gets this many iterations on
    #: the training signal the fit they extend misfits most, then only the
    #: ``race_survivors`` best carry on, on every signal, for the rest of the
    #: budget (see :func:`~sklearn_pnlss.gap.stages.added_effects`).  On
    #: family t, raced on every signal, the same 12 verdicts and pairs as
    #: every pair fitted in full, the right pair among the 3 carried on in
    #: every case; the diagnosis 46 s at the median instead of 57 s.  Raced
    #: on one signal of four, the same 12 verdicts and pairs, 26 s at the
    #: median (family t's cubic spring with friction: its forward selection
    #: 9.3 s instead of 25.8 s, ``bench_gap_time.py``).
    race_iterations: int = 4
    race_survivors: int = 3

    # -- the verdict -------------------------------------------------------------------
    #: A gap smaller than this above the noise floor is not worth a diagnosis, dB.
    min_excess_db: float = 0.5
    #: The same when the floor is an estimate (a model's residual), dB.
    estimated_floor_min_excess_db: float = 1.0
    #: Fraction of the gap's excess over the noise (in dB) a candidate must remove.
    explained_closure: float = 0.9
    #: Closure difference below which two candidates count as equally good, on
    #: top of the statistical spread of the noise; also the share of the
    #: nominal's excess (dB) a candidate must gain over the refit it contains
    #: to be refined.
    tie_closure: float = 0.02
    #: Closure the black box must reach to stand for "as far as a model can
    #: close the gap" when the floor is an estimate.
    black_box_min_closure: float = 0.8
    #: Floor assumed without any noise estimate, below the nominal gap, dB.
    no_floor_db: float = 60.0
    #: Draws of the best candidate's parameters from their covariance that
    #: tell a validation signal it cannot pin down (a chaotic orbit, a jump).
    sensitivity_draws: int = 6


#: The settings every diagnosis reads.
SETTINGS = GapSettings()
