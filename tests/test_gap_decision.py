"""The verdict of the gap diagnosis (sklearn_pnlss.gap.verdict.decision) on
constructed evidence: validation errors of chosen mean square, so that
every closure, p-value and choice is known in advance."""
import numpy as np
import pytest
from scipy import stats

from sklearn_pnlss.gap.fitting.calibrate import EffectFit
from sklearn_pnlss.gap.settings import SETTINGS
from sklearn_pnlss.gap.verdict.decision import decide
from gap_signals import stub_effect
from sklearn_pnlss.gap.verdict.noise_floor import NoiseFloor, gap_test

S2 = 1e-12  # noise variance, m^2
NOISE = NoiseFloor(variance=S2, spectrum=np.full(513, S2), dof_per_sample=1.0)
SIZE = 100_000


def _fit(name, n_params=1, recalibration=False):
    """A fitted candidate as decide sees it (only names and counts matter)."""
    effect = stub_effect(name, n_params, recalibration)
    return EffectFit(effect, np.zeros(n_params), {"p0": 1.5}, train_mse=4e-12, n_evaluations=1,
                     converged=True, message="")


def _with_mse(mse, size=SIZE):
    """A simulated signal whose mean square error against zero is ``mse``."""
    return np.full(size, np.sqrt(mse))


def _decide(before, candidates, *, black_box=None, noise=NOISE, size=SIZE):
    """``before``: nominal mse per signal; ``candidates``: (fit, mse per
    signal, or None for a diverged simulation) pairs."""
    y_meas = [np.zeros(size) for _ in before]
    y_nominal = [_with_mse(b, size) for b in before]
    y_effects = [None if m is None else [_with_mse(a, size) for a in m] for _, m in candidates]
    y_bb = None if black_box is None else [None if a is None else _with_mse(a, size) for a in black_box]
    return decide([f for f, _ in candidates], y_meas, y_nominal, y_effects, y_bb, noise, significance=1e-3)


def test_closure_is_the_share_of_the_excess_removed_in_db():
    """Nominal 40 dB above the noise; a candidate leaving 20 dB closes 50 %,
    one leaving 4 dB 90 %, one down to the noise 100 %, one worse than the
    nominal less than nothing."""
    fits = [(_fit("half"), [1e-10]), (_fit("ninety"), [10**0.4 * S2]), (_fit("all"), [0.5 * S2]),
            (_fit("worse"), [1e-6])]
    d = _decide([1e-8], fits)
    closure = {r.name: r.closure for r in d.ranking}
    assert closure["half"] == pytest.approx(0.5)
    assert closure["ninety"] == pytest.approx(0.9)
    assert closure["all"] == pytest.approx(1.0)
    assert closure["worse"] == pytest.approx(1 - 60 / 40)
    assert [r.name for r in d.ranking] == ["all", "ninety", "half", "worse"]
    best = d.ranking[0]
    assert best.gap_before_db == pytest.approx(-80.0)
    assert best.gap_after_db == pytest.approx(10 * np.log10(0.5 * S2))
    assert best.shrink_db == pytest.approx(-80.0 - 10 * np.log10(0.5 * S2))
    assert d.best_effect == "all" and d.explained and d.significant
    assert d.noise_floor_db == pytest.approx(-120.0)
    assert d.gap_before_db == pytest.approx(-80.0)
    assert best.train_gap_db == pytest.approx(10 * np.log10(4e-12))


def test_closure_pools_signals_by_their_own_excess():
    """Signal 1 is 40 dB above the noise, signal 2 at the noise: a candidate
    that closes signal 1 but puts signal 2 10 dB above the noise closes
    1 - 10 / 40 = 75 % of the pooled gap."""
    d = _decide([1e-8, S2], [(_fit("c"), [S2, 10 * S2])])
    assert d.ranking[0].closure == pytest.approx(0.75)
    assert d.per_signal_before_db == pytest.approx([-80.0, -120.0])
    assert d.ranking[0].per_signal_after_db == pytest.approx([-120.0, -110.0])


def test_no_gap_at_the_noise_floor():
    """A nominal error at the noise level: no verdict, p-value about 1/2
    (chi-square at its mean), whatever the candidates do."""
    d = _decide([S2], [(_fit("c"), [0.5 * S2])])
    assert d.best_effect is None and not d.significant
    assert 0.3 < d.p_value < 1.0
    assert "no significant gap" in d.reason


def test_small_excess_is_no_gap_even_when_significant():
    """With 1e5 noise samples per signal an excess of 0.4 dB is far beyond
    chance, but below SETTINGS.min_excess_db it is not worth a diagnosis; 0.6 dB is."""
    assert SETTINGS.min_excess_db == 0.5
    small = _decide([10**0.04 * S2], [(_fit("c"), [S2])])
    assert small.p_value < 1e-10
    assert small.best_effect is None and not small.significant
    above = _decide([10**0.06 * S2], [(_fit("c"), [S2])])
    assert above.significant and above.best_effect == "c"


def test_p_value_is_chi_square_with_the_noise_dof():
    """gap_test: the mean square over n samples of noise with nu = dof * n
    degrees of freedom is chi-square(nu) / nu; decide multiplies the smallest
    p-value by the number of signals (Bonferroni)."""
    half_dof = NoiseFloor(S2, np.full(513, S2), dof_per_sample=0.5)
    assert gap_test(1.01 * S2, half_dof, 20_000) == pytest.approx(stats.chi2.sf(1.01 * 10_000, 10_000))
    assert gap_test(S2, NOISE, 10**6) == pytest.approx(0.5, abs=0.01)
    before = [1.02 * S2, 1.5 * S2]
    d = _decide(before, [(_fit("c"), [S2, S2])], size=1000)
    assert d.p_value == pytest.approx(2 * stats.chi2.sf(1.5 * 1000, 1000))


def test_recalibration_is_preferred_within_reach_of_the_best():
    """New physics closing 97 % against a refit of the nominal parameters
    closing 96 %: within SETTINGS.tie_closure (plus the noise's spread, 0.14 % here),
    the refit wins; at 90 % it does not."""
    assert SETTINGS.tie_closure == 0.02
    excess = 40.0
    nu = 1.0 * SIZE
    spread = 10 * np.log10(1 + 3 * np.sqrt(2 / nu)) / excess
    assert spread == pytest.approx(1.447e-3, rel=1e-3)

    def after(closure):  # mean square leaving (1 - closure) of 40 dB
        return S2 * 10 ** ((1 - closure) * excess / 10)

    d = _decide([1e-8], [(_fit("cubic"), [after(0.97)]), (_fit("recal", 3, True), [after(0.96)])])
    assert d.ranking[0].name == "cubic"
    assert d.best_effect == "recal"
    assert "as good within the noise: cubic" in d.reason
    d = _decide([1e-8], [(_fit("cubic"), [after(0.97)]), (_fit("recal", 3, True), [after(0.90)])])
    assert d.best_effect == "cubic"
    # at the edge of reach: 0.97 - 0.02 - spread, just inside and just outside
    inside = 0.97 - SETTINGS.tie_closure - 0.9 * spread
    outside = 0.97 - SETTINGS.tie_closure - 1.1 * spread
    for closure, chosen in ((inside, "r"), (outside, "cubic")):
        d = _decide([1e-8], [(_fit("cubic"), [after(0.97)]), (_fit("r", 3, True), [after(closure)])])
        assert d.best_effect == chosen


def test_fewer_parameters_win_among_equivalent_candidates():
    """Two new effects within reach of each other: the one with fewer
    parameters is chosen, though it closes slightly less."""
    d = _decide([1e-8], [(_fit("two", 2), [1.2 * S2]), (_fit("one", 1), [1.3 * S2]),
                         (_fit("three", 3), [1.25 * S2])])
    assert [r.name for r in d.ranking] == ["two", "three", "one"]
    assert d.best_effect == "one"


def test_unexplained_when_the_best_closes_too_little():
    """The best candidate closes 80 % < SETTINGS.explained_closure: unexplained,
    and the black box's closure (95 %) is reported as the yardstick."""
    assert SETTINGS.explained_closure == 0.9
    d = _decide([1e-8], [(_fit("c"), [10**0.8 * S2])], black_box=[10**0.2 * S2])
    assert d.best_effect == "unexplained" and not d.explained and d.significant
    assert d.ranking[0].closure == pytest.approx(0.8)
    assert d.black_box_closure == pytest.approx(0.95)
    assert d.black_box_gap_db == pytest.approx(10 * np.log10(10**0.2 * S2))
    assert "closes only 80 %" in d.reason and "black box closes 95 %" in d.reason


def test_diverged_candidates_and_black_box_rank_last():
    d = _decide([1e-8], [(_fit("diverged"), None), (_fit("ok"), [S2])], black_box=[None])
    assert [r.name for r in d.ranking] == ["ok", "diverged"]
    assert d.ranking[1].closure == -np.inf and d.ranking[1].gap_after_db == np.inf
    assert d.black_box_closure == -np.inf and d.black_box_gap_db == np.inf
    assert d.best_effect == "ok"


def test_without_noise_floor_the_floor_is_60_db_below_the_gap():
    """No noise estimate: no test (p is NaN), and closure counts against a
    floor 60 dB under the nominal gap, so removing 30 dB closes 50 %."""
    d = _decide([1e-8], [(_fit("c"), [1e-11])], noise=None)
    assert np.isnan(d.p_value) and np.isnan(d.noise_floor_db)
    assert d.significant
    assert d.ranking[0].closure == pytest.approx(0.5)
    assert d.best_effect == "unexplained"


def test_estimated_floor_needs_a_dB_of_excess():
    """A nominal 0.7 dB above a floor read from a model's residual is no
    gap (the estimate is good to about a dB); above a floor from repeated
    periods it is one."""
    estimated = NoiseFloor(S2, np.full(513, S2), dof_per_sample=1.0, source="non_excited_lines")
    before = [10**0.07 * S2] * 2
    assert _decide(before, [(_fit("c"), [S2, S2])], noise=estimated).best_effect is None
    assert _decide(before, [(_fit("c"), [S2, S2])]).best_effect == "c"


def _decide_with(before, candidates, combinations):
    """``_decide`` with the forward selection's combinations (fit, mse per
    signal), each extending the one before."""
    y_meas = [np.zeros(SIZE) for _ in before]
    return decide([f for f, _ in candidates], y_meas, [_with_mse(b) for b in before],
                  [[_with_mse(a) for a in m] for _, m in candidates], None, NOISE, significance=1e-3,
                  combinations=[f for f, _ in combinations],
                  y_combinations=[[_with_mse(a) for a in m] for _, m in combinations])


def test_an_added_effect_names_the_pair_s_stronger_part_as_the_main_one():
    """40 dB above the noise: a flexible effect closes 55 % alone, the
    cubic spring 25 %; the cubic spring with friction closes all of it, and
    a third effect adds nothing beyond the tie.  The pair's effect that
    closes more alone (the cubic spring) is the main one, friction is
    added, the third is not."""
    d = _decide_with([1e-8], [(_fit("flexible", 3), [10**1.8 * S2]), (_fit("cubic"), [10**3 * S2])],
                     [(_fit("cubic + friction", 2), [S2]), (_fit("cubic + friction + other", 3), [0.99 * S2])])
    assert d.best_effect == "cubic" and d.main_effect == "cubic" and d.explained
    assert [r.name for r in d.added_effects] == ["cubic + friction"]
    assert "with friction added, 100 %" in d.reason


def test_a_pair_that_does_not_pay_leaves_the_verdict():
    """The pair closes 56 % where the best single closes 55 %: within the
    tie, so the verdict is the single one's (unexplained), naming it as the
    main effect."""
    d = _decide_with([1e-8], [(_fit("flexible", 3), [10**1.8 * S2]), (_fit("cubic"), [10**3 * S2])],
                     [(_fit("cubic + friction", 2), [10**1.76 * S2])])
    assert d.best_effect == "unexplained" and d.main_effect == "flexible" and not d.added_effects
