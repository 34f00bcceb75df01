"""Sim-to-real gap diagnosis on small data whose missing effect is known."""
import json
import warnings
from dataclasses import replace

import numpy as np
import pytest

from sklearn_pnlss.gap import GapDiagnosis, default_effects
from sklearn_pnlss.gap.candidates.clues import DataClues, read_clues
from sklearn_pnlss.gap.candidates.effects import Scales, make_effect
from sklearn_pnlss.gap.candidates.stiffness_start import measured_stiffness_change, recalibration_start
from sklearn_pnlss.gap.verdict.noise_floor import drift_free_variance, estimate_noise
from sklearn_pnlss.gap.fitting.simulate import (
    SignalSet,
    detect_period,
    measured_starts,
    prime_factors,
    simulate_signals,
)
from sklearn_pnlss.gap.readings import content_limit, signal_derivative
from sklearn_pnlss.physics.oscillator import STATE_Z
from sklearn_pnlss.physics.resampling import decimate_fir, upsample_fft
from sklearn_pnlss.physics import (
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    DeadZoneSpring,
    Oscillator,
    QuadraticDamping,
    SeriesDamper,
    StiffnessDrift,
)
from sklearn_pnlss.signals import linear_chirp, multisine

from gap_signals import FS, N, gap_data

NOMINAL = Oscillator(2.0, 10.0, 5e4)
FAST = dict(fs=FS, period=N, oversampling=10, fit_oversampling=5, black_box=False)


@pytest.fixture(scope="module")
def cubic_case():
    real = NOMINAL.with_forces([CubicStiffness(1e8)])
    u, y, u_val, y_val = gap_data(real)
    diag = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", "quadratic_damping", "recalibration"],
                        **FAST).fit(u, y)
    return diag, diag.report(u_val, y_val)


def test_default_effects_are_the_documented_ones():
    assert default_effects() == [
        "hysteresis", "cubic_stiffness", "quadratic_stiffness", "coulomb_friction", "quadratic_damping",
        "backlash", "input_saturation", "input_delay", "second_mode", "stiffness_drift", "recalibration",
    ]


def test_prime_factor_chain():
    assert prime_factors(20) == (2, 2, 5)
    assert prime_factors(7) == (7,)


def test_cubic_stiffness_is_found_and_recovered(cubic_case):
    diag, report = cubic_case
    assert report.best_effect == "cubic_stiffness"
    best = report.ranking[0]
    assert best.name == "cubic_stiffness"
    assert best.params["k3"] == pytest.approx(1e8, rel=0.01)
    # the gap closes down to the noise floor: within 1 dB of it
    assert best.closure > 0.98
    assert best.gap_after_db < report.noise_floor_db + 1.0
    assert best.shrink_db > 20
    # the other candidates explain far less
    others = {r.name: r.closure for r in report.ranking[1:]}
    assert max(others.values()) < 0.8
    # one effect explains it: nothing is added
    assert diag.combinations_ == [] and report.added_effects == [] and report.main_effect == "cubic_stiffness"


def test_a_second_effect_is_added_where_it_pays():
    """A cubic spring with dry friction (0.3 N, a third of the cubic's
    force): the cubic spring alone, its damping refitted, closes about
    half of the gap; with friction added the gap closes to the noise, and
    the friction and the nominal come back to their true values."""
    real = NOMINAL.with_forces([CubicStiffness(1e8), CoulombFriction(0.3, 2e-3)])
    u, y, u_val, y_val = gap_data(real, seed=9)
    diag = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", "coulomb_friction", "quadratic_damping",
                                          "recalibration"], **FAST).fit(u, y)
    report = diag.report(u_val, y_val)
    assert report.best_effect == report.main_effect == "cubic_stiffness" and report.explained
    assert report.added_effects == ["coulomb_friction"]
    pair = report.decision.added_effects[0]
    assert next(r for r in report.ranking if r.name == "cubic_stiffness").closure < 0.7  # measured: 50 %
    assert pair.closure > 0.98 and pair.gap_after_db < report.noise_floor_db + 0.5
    assert pair.params["fc"] == pytest.approx(0.3, rel=0.02)
    assert pair.params["k3"] == pytest.approx(1e8, rel=0.01)
    assert abs(report.decision.recalibrated.get("damping", 0.0)) < 0.01
    assert "with coulomb_friction added" in str(report)


def test_noise_floor_is_the_simulated_noise(cubic_case):
    diag, _ = cubic_case
    # 2e-6 m rms at the integration rate, band-limited and decimated
    assert 1.0e-6 < diag.noise_.rms < 2.1e-6


def test_where_the_gap_lies(cubic_case):
    _, report = cubic_case
    freq = report.where.frequency
    bands = freq.bands
    # a stiffness nonlinearity shows where the response is large: around the
    # 25 Hz resonance, far above the noise there
    worst = max(bands, key=lambda b: b.gap_db - b.noise_db)
    assert worst.f_lo <= 25.2 <= worst.f_hi
    assert worst.n_significant > 0.5 * worst.n_lines
    fmap = report.where.state_plane
    finite = np.isfinite(fmap.force)
    assert finite.sum() > 20
    # the missing force k3 y^3 is odd in displacement: the map's mean force at
    # the largest displacements has the sign of y and about its size
    y_mid = 0.5 * (fmap.displacement_edges[1:] + fmap.displacement_edges[:-1])
    rows = np.isfinite(fmap.force).any(axis=1)
    col = np.full(rows.size, np.nan)
    col[rows] = np.nanmean(fmap.force[rows], axis=1)
    ok = np.isfinite(col)
    slope = np.polyfit(y_mid[ok] ** 3, col[ok], 1)[0]
    assert slope == pytest.approx(1e8, rel=0.3)
    sweep = report.where.time.sweeps[0].windows
    assert sweep[0].frequency == pytest.approx(15.0, abs=2.0)


def test_report_text_dict_and_plot(cubic_case):
    _, report = cubic_case
    text = str(report)
    assert "verdict: cubic_stiffness" in text and "k3 = " in text
    d = report.to_dict()
    json.dumps(d)  # plain types only
    assert d["best_effect"] == "cubic_stiffness"
    assert d["ranking"][0]["params"]["k3"] == pytest.approx(1e8, rel=0.01)
    import matplotlib

    matplotlib.use("Agg")
    fig = report.plot()
    assert len(fig.axes) >= 6
    bars = fig.axes[0].patches
    assert len(bars) == len(report.ranking)


def test_no_false_alarm_without_gap():
    u, y, u_val, y_val = gap_data(NOMINAL, seed=3)
    report = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", "recalibration"], **FAST).fit(u, y).report(
        u_val, y_val)
    assert report.best_effect is None and not report.significant
    assert abs(report.gap_db - report.noise_floor_db) < 0.5


def test_parameter_error_is_recalibration():
    real = Oscillator(2.0, 10.0, 1.05 * 5e4)
    u, y, u_val, y_val = gap_data(real, seed=4)
    report = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", "recalibration"], **FAST).fit(u, y).report(
        u_val, y_val)
    assert report.best_effect == "recalibration"
    recal = next(r for r in report.ranking if r.name == "recalibration")
    assert recal.params["stiffness"] == pytest.approx(1.05 * 5e4, rel=1e-3)


def test_missing_candidate_is_unexplained():
    real = NOMINAL.with_forces([QuadraticDamping(15.0)])
    u, y, u_val, y_val = gap_data(real, seed=5)
    report = GapDiagnosis(NOMINAL, effects=["quadratic_stiffness", "input_delay"], **FAST).fit(u, y).report(
        u_val, y_val)
    assert report.best_effect == "unexplained"
    assert report.significant


def test_user_force_element_is_a_candidate():
    real = NOMINAL.with_forces([QuadraticDamping(15.0)])
    u, y, u_val, y_val = gap_data(real, seed=6)
    report = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", QuadraticDamping(5.0)], **FAST).fit(u, y).report(
        u_val, y_val)
    assert report.best_effect == "QuadraticDamping"
    assert report.ranking[0].params["c2"] == pytest.approx(15.0, rel=0.02)


def test_a_viscoelastic_mount_is_named_and_recovered():
    """The effect added as one class and one force element (a spring and a
    damper in series, relaxing at 40 Hz beside the nominal's 25 Hz mode):
    named against a second mode and a recalibration, which also change the
    structure linearly, and closing the gap to the noise.  With the nominal
    exact its spring and damper are recovered to 0.1 %; with the nominal
    freed, the mount and the nominal's damping trade off within the noise
    (measured: ks 2.4 % off, the damping 5 %, at the floor)."""
    ks, cs = 1e4, 1e4 / (2 * np.pi * 40.0)
    real = NOMINAL.with_forces([SeriesDamper(cs, ks)])
    u, y, u_val, y_val = gap_data(real, seed=8)
    candidates = ["viscoelastic_mount", "second_mode", "recalibration"]
    for free_nominal, tolerance in ((False, 1e-3), (True, 0.05)):
        report = GapDiagnosis(NOMINAL, effects=candidates, free_nominal=free_nominal, **FAST).fit(u, y).report(
            u_val, y_val)
        assert report.best_effect == "viscoelastic_mount"
        mount = report.ranking[0]
        assert mount.gap_after_db < report.noise_floor_db + 0.5
        assert mount.params["ks"] == pytest.approx(ks, rel=tolerance)
        assert mount.params["cs"] == pytest.approx(cs, rel=tolerance)
    assert "viscoelastic_mount" not in default_effects()  # by request until the families run with it


def test_drift_periods_continue_from_the_initial_steady_state():
    """A drifting structure's periods differ; without drift they repeat."""
    X, _ = multisine(N, fs=FS, rms=50.0, n_periods=3, n_realizations=1, random_state=0)
    sig = SignalSet.from_signals([X[0, :, 0]], N, FS, 10)
    still = simulate_signals(NOMINAL, sig)[0].reshape(3, N)
    np.testing.assert_allclose(still[1], still[0])
    drifting = simulate_signals(NOMINAL.with_forces([StiffnessDrift(-500.0)]), sig)[0].reshape(3, N)
    # the first samples continue the steady state of the undrifted structure
    assert np.max(np.abs(drifting[0, :20] - still[0, :20])) < 1e-3 * np.abs(still).max()
    change = [np.sqrt(np.mean((drifting[p] - still[p]) ** 2)) for p in range(3)]
    assert change[0] < change[1] < change[2]


def test_steady_state_search_starts_where_the_measurement_does():
    """A stiffening spring driven above its resonance has two stable steady
    states; the one a record shows is found again from its period start,
    where a search from rest finds the other."""
    n, fs, r = 2000, 15000.0, 20
    u = 40.0 * np.sin(2 * np.pi * 4 * np.arange(n) / n)  # 30 Hz; the resonance at 25 Hz
    osc = NOMINAL.with_forces([CubicStiffness(1e8)])
    lower = simulate_signals(osc, SignalSet.from_signals([u], n, fs, r))[0]
    # the upper branch: 150 periods from a start 20 mm into the swing
    u_fine = upsample_fft(u, r, periodic=True)
    kick = np.zeros(STATE_Z)
    kick[1] = 2e-2 * 2 * np.pi * 4 * fs / n
    swing = osc.simulate_fine(np.tile(u_fine, 150), fs=r * fs, periodic=False, initial_state=kick).y
    upper = decimate_fir(swing[-u_fine.size:], prime_factors(r), periodic=True)
    assert np.abs(upper).max() > 8 * np.abs(lower).max()
    # measured on the upper branch: two periods, noise 1e-3 of the peak
    y = np.tile(upper, 2) + 1e-3 * np.abs(upper).max() * np.random.RandomState(0).standard_normal(2 * n)
    starts = measured_starts([y], [signal_derivative(y, fs, 2, n, f_max=content_limit([u], fs))], [2], n)
    found = simulate_signals(osc, SignalSet.from_signals([np.tile(u, 2)], n, fs, r, starts=starts))[0]
    np.testing.assert_allclose(found, np.tile(upper, 2), atol=1e-6 * np.abs(upper).max())
    # a linear structure has one steady state, wherever the search starts
    linear = [simulate_signals(NOMINAL, SignalSet.from_signals([u], n, fs, r, starts=s))[0]
              for s in (None, starts[:1])]
    np.testing.assert_allclose(linear[1], linear[0], atol=1e-8 * np.abs(linear[0]).max())


def test_a_training_signal_that_never_settled_is_left_out():
    """A record started before the start-up transient died is no steady
    state: its periods differ far more than the others', it is left out of
    the fits and the noise floor, with a warning and a line in the report."""
    real = NOMINAL.with_forces([CubicStiffness(1e8)])
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=3, n_realizations=3, random_state=3)
    u = [x[:, 0] for x in X]
    rng = np.random.RandomState(0)
    y = simulate_signals(real, SignalSet.from_signals(u, N, FS, 10), noise_rms=2e-6, random_state=rng)
    y[1] = simulate_signals(real, SignalSet(u[1:2], [0], None, FS, 10, (2, 5)), noise_rms=2e-6,
                            random_state=rng)[0]  # from rest
    diag = GapDiagnosis(NOMINAL, effects=["cubic_stiffness", "recalibration"], **FAST)
    with pytest.warns(UserWarning, match="Training signal 1 never settles"):
        diag.fit(u, y)
    assert diag.unsettled_signals_ == [1]
    settled_floor = estimate_noise([y[0], y[2]], N)
    assert diag.noise_.variance == pytest.approx(settled_floor.variance)
    report = diag.report(*gap_data(real)[2:])
    assert report.best_effect == "cubic_stiffness"
    assert "training signal 1 left out" in str(report)
    assert report.to_dict()["unsettled_signals"] == [1]


def test_the_leading_candidate_is_carried_on_past_its_budget(monkeypatch):
    """The verdict rests on the best candidate: a fit of it that stops on
    its iteration budget above the noise floor gets further budgets (on the
    benchmark's stiff backlash, family d seed 101: -97.0 -> -103.0 dB of
    training error, the noise); one at the floor is left as it is."""
    import sklearn_pnlss.gap.stages as stages

    real = NOMINAL.with_forces([DeadZoneSpring(1e4, 1.5e-3)])

    def backlash_fit(budgets, n_periods):
        monkeypatch.setattr(stages, "SETTINGS", replace(stages.SETTINGS, leader_budgets=budgets))
        u, y, _, _ = gap_data(real, n_periods=n_periods)
        # fitted at the reporting rate only: the budget is the one solve's
        diag = GapDiagnosis(NOMINAL, effects=["backlash", "quadratic_damping"], max_nfev=2,
                            free_nominal=False, **{**FAST, "fit_oversampling": FAST["oversampling"]}).fit(u, y)
        return next(f for f in diag.fits_ if f.effect.name == "backlash")

    # one period per signal: no floor before the fits, so it is carried on
    stopped, carried = backlash_fit(0, 1), backlash_fit(2, 1)
    assert not stopped.converged
    assert carried.train_mse <= stopped.train_mse
    assert carried.n_evaluations > stopped.n_evaluations
    # two periods: the floor is known and the stopped fit sits on it
    stopped, carried = backlash_fit(0, 2), backlash_fit(2, 2)
    assert not stopped.converged
    assert carried.n_evaluations == stopped.n_evaluations


def test_second_mode_start_read_from_the_frf():
    """A lightly damped mode at 60 Hz (the nominal's is 25 Hz): the FRF start
    lands on it, where the listed starts alone settled on a wrong resonance."""
    m2, f2, zeta = 0.2, 60.0, 0.02
    w2 = 2 * np.pi * f2
    real = NOMINAL.with_forces([CoupledMass(m2, 2 * zeta * m2 * w2, m2 * w2**2)])
    u, y, _, _ = gap_data(real, seed=7, noise=1e-7)
    y_nominal = simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))
    change = measured_stiffness_change(u, y, y_nominal, N, FS)
    scales = Scales(force=50.0, displacement=1e-3, velocity=0.1, duration=3.0, u_peak=150.0, fs=FS)
    theta = make_effect("second_mode").data_starts(DataClues(change), NOMINAL, scales)[0]
    w1 = np.sqrt(5e4 / 2.0)
    assert theta[0] * 2.0 == pytest.approx(m2, rel=0.1)
    assert theta[1] * w1 == pytest.approx(w2, rel=0.01)
    assert theta[2] == pytest.approx(zeta, rel=0.3)
    # the same change read as a recalibration is a poor fit, but finite
    assert np.all(np.isfinite(recalibration_start(change, NOMINAL, scales)))


def test_backlash_start_read_from_the_missing_force():
    """The dead-zone spring fitted to the force the nominal leaves
    unbalanced along the measured motion lands on the true rate and
    clearance, without a single simulation of the candidate: the grid's
    clearance refined with the candidate's own rounded spring (the grid
    alone left both 0.6-0.8 % off)."""
    real = NOMINAL.with_forces([DeadZoneSpring(3e4, 1.5e-3)])
    u, y, _, _ = gap_data(real, seed=9, noise=1e-7)
    train = SignalSet.from_signals(u, N, FS, 10)
    clues = read_clues(NOMINAL, u, y, simulate_signals(NOMINAL, train), train.n_periods, N, FS)
    scales = Scales(force=50.0, displacement=1e-3, velocity=0.1, duration=3.0, u_peak=150.0, fs=FS)
    kb, gap = make_effect("backlash").data_starts(clues, NOMINAL, scales)[0] * [scales.stiffness, scales.displacement]
    assert kb == pytest.approx(3e4, rel=0.005)  # measured: 29948 N/m, 1.4973 mm
    assert gap == pytest.approx(1.5e-3, rel=0.005)


def test_recalibration_start_is_exact_for_a_linear_error():
    real = Oscillator(2.2, 14.0, 1.05 * 5e4)
    u, y, _, _ = gap_data(real, seed=8, noise=0.0)
    y_nominal = simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))
    scales = Scales(force=50.0, displacement=1e-3, velocity=0.1, duration=3.0, u_peak=150.0, fs=FS)
    theta = recalibration_start(measured_stiffness_change(u, y, y_nominal, N, FS), NOMINAL, scales)
    assert 2.0 * (1 + theta[0]) == pytest.approx(2.2, rel=1e-3)
    assert 10.0 + theta[1] * scales.force / scales.velocity == pytest.approx(14.0, rel=1e-2)
    assert 5e4 + theta[2] * scales.stiffness == pytest.approx(1.05 * 5e4, rel=1e-3)


def test_noise_floor_is_not_raised_by_a_slow_drift():
    """Period-to-period change of a drifting structure is not noise: the
    floor from the detrended spread stays near the true noise while the
    plain spread rises by tens of dB."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=5, n_realizations=2, random_state=0)
    sig = SignalSet.from_signals([x[:, 0] for x in X], N, FS, 10)
    noise = 2e-6
    y = simulate_signals(NOMINAL.with_forces([StiffnessDrift(-30.0)]), sig, noise_rms=noise, random_state=0)
    still = simulate_signals(NOMINAL, sig, noise_rms=noise, random_state=0)

    def floor_db(s):
        w = np.full(s.size, 2.0)
        w[0] = w[-1] = 1.0
        return 10 * np.log10(np.sum(w * s) / N)

    plain = np.mean([np.var(np.fft.rfft(v.reshape(5, N), axis=1) / np.sqrt(N), axis=0, ddof=1) for v in y], axis=0)
    true_db = floor_db(drift_free_variance(still, N))
    assert floor_db(plain) > true_db + 20  # measured: +32 dB, detrended +1.7 dB
    assert floor_db(drift_free_variance(y, N)) < true_db + 3
    # without drift the detrended spread is the plain one, within its scatter
    plain_still = np.mean([np.var(np.fft.rfft(v.reshape(5, N), axis=1) / np.sqrt(N), axis=0, ddof=1)
                           for v in still], axis=0)
    assert abs(true_db - floor_db(plain_still)) < 0.3


@pytest.mark.parametrize("kwargs, match", [
    (dict(effects=["no_such_effect"]), "unknown effect"),
    (dict(effects=["cubic_stiffness", "cubic_stiffness"]), "twice"),
    (dict(effects=[]), "empty"),
    (dict(effects=[3.0]), "ForceElement"),
])
def test_bad_effects(kwargs, match):
    u, y, _, _ = gap_data(NOMINAL, seed=1, noise=0.0)
    with pytest.raises((ValueError, TypeError), match=match):
        GapDiagnosis(NOMINAL, **{**FAST, **kwargs}).fit(u, y)


def test_bad_signals():
    u, y, _, _ = gap_data(NOMINAL, seed=1, noise=0.0)
    diag = GapDiagnosis(NOMINAL, effects=["cubic_stiffness"], **FAST)
    with pytest.raises(ValueError, match="one channel"):
        diag.fit([np.column_stack([u[0], u[0]])], [y[0]])
    with pytest.raises(ValueError, match="samples"):
        diag.fit([u[0]], [y[0][:-1]])
    with pytest.raises(ValueError, match="signals"):
        diag.fit(u, y[:1])
    with pytest.raises(ValueError, match="constant"):
        diag.fit([np.zeros(N)], [np.zeros(N)])
    with pytest.raises(ValueError, match="NaN"):
        diag.fit([np.full(N, np.nan)], [y[0][:N]])


def test_verbose_announces_each_candidate_as_it_is_fitted(capsys):
    from sklearn_pnlss.app.gap_demo import run_gap_demo

    run_gap_demo(None, n_samples=1024, n_jobs=2, plot=False, progress=True)
    lines = [line for line in capsys.readouterr().out.splitlines() if " done, " in line]
    n = len(lines)
    assert n >= 10  # every default candidate and the black box
    assert [int(line.split("]")[1].split("/")[0]) for line in lines] == list(range(1, n + 1))
    assert any("the black box" in line for line in lines)
    assert all("training" in line and "dB" in line for line in lines if "black box" not in line)


def test_forgetting_period_on_periodic_data_warns():
    """Steady-state signals of two periods and period=None: a UserWarning
    names the period the inputs repeat with and the parameter to set; none
    with the period given."""
    u, y, u_val, y_val = gap_data(NOMINAL, seed=1, noise=1e-7)
    forgot = GapDiagnosis(NOMINAL, effects=["cubic_stiffness"], **{**FAST, "period": None})
    with pytest.warns(UserWarning, match=r"repeat every 1024 samples \(1\.365 s, 2 periods per signal\).*"
                                         r"pass period=1024\."):
        forgot.fit(u, y)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        GapDiagnosis(NOMINAL, effects=["cubic_stiffness"], **FAST).fit(u, y)


def test_single_steady_state_periods_without_period_warn():
    """One steady-state period does not repeat, yet simulated from rest its
    start-up transient counts as gap.  With period=None a training or
    validation signal whose misfit holds the nominal's start-up transient is
    named (here with a cubic spring the nominal lacks: the model is off,
    the transient is still recognised); records from rest (a sweep, noise
    filtered from rest) are not."""
    real = NOMINAL.with_forces([CubicStiffness(1e8)])
    u, y, u_val, y_val = gap_data(real, seed=1, n_periods=1)
    forgot = GapDiagnosis(NOMINAL, effects=["cubic_stiffness"], **{**FAST, "period": None})
    with pytest.warns(UserWarning, match=r"training signals \[0, 1\] look like steady-state periods.*"
                                         r"pass period=1024\."):
        forgot.fit(u, y)
    with pytest.warns(UserWarning, match=r"validation signals \[0\] look like"):
        forgot.report(u_val, y_val)  # one period (named) and a sweep from rest (not)
    rng = np.random.RandomState(0)
    noise = np.convolve(rng.standard_normal(4000), np.hanning(9), "same")
    u_rest = [u_val[1], 50.0 * noise / noise.std()]
    rest = SignalSet.from_signals(u_rest, N, FS, 10)
    y_rest = simulate_signals(real, rest, noise_rms=2e-6, random_state=rng)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        forgot.fit(u_rest, y_rest)
        forgot.report(u_rest, y_rest)


def test_detect_period():
    """Multisines repeated, with a measured force's noise (1 % of the rms),
    or slow (20 Hz at 7.5 kHz: neighbouring lags correlate too): their
    period; single periods, a sweep or noise: None."""
    rng = np.random.RandomState(0)
    X, _ = multisine(N, fs=FS, rms=50.0, n_periods=3, n_realizations=2, random_state=0)
    assert detect_period([x[:, 0] + 0.5 * rng.standard_normal(3 * N) for x in X]) == N
    slow, _ = multisine(N, fs=10 * FS, f_band=(1.0, 20.0), rms=1.0, n_periods=2, random_state=0)
    assert detect_period([slow[0, :, 0]]) == N
    assert detect_period([X[0, :N, 0], X[1, :N, 0]]) is None
    assert detect_period([linear_chirp(np.arange(3000) / FS, f_start=15.0, rate=8.0, amplitude=10.0)]) is None
    assert detect_period([rng.standard_normal(4 * N)]) is None
