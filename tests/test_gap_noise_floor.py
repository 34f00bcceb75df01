"""The noise floor of the gap diagnosis when no period repeats
(sklearn_pnlss.gap.verdict.noise_floor), and the verdict it sets.

Issue 16, item 3: nominal + ``CubicStiffness(-1e8)``, one period per
training signal.  The cubic term takes the error from about -62 dB down to
the noise (-114.7 dB); without a period-to-period spread the verdict used
to be "gap not explained ... closes only 85 %" with "noise floor nan dB".
The floor now comes from what the data give, and the report names it.
"""
import numpy as np
import pytest

from sklearn_pnlss.gap import GapDiagnosis
from sklearn_pnlss.gap.fitting.calibrate import EffectFit
from sklearn_pnlss.gap.settings import SETTINGS
from sklearn_pnlss.gap.verdict.decision import decide
from gap_signals import stub_effect
from sklearn_pnlss.gap.verdict.noise_floor import (
    NoiseFloor,
    estimate_noise,
    non_excited_noise,
    repeated_input_noise,
    residual_noise,
    unsettled_signals,
)
from sklearn_pnlss.gap.fitting.simulate import SignalSet, simulate_signals
from sklearn_pnlss.physics import CubicStiffness, Oscillator
from sklearn_pnlss.signals import linear_chirp, multisine

FS, N = 750.0, 1024
NOMINAL = Oscillator(2.0, 10.0, 5e4)
REAL = NOMINAL.with_forces([CubicStiffness(-1e8)])
NOISE_RMS = 2e-6  # at the integration rate, band-limited to the data's Nyquist
FAST = dict(fs=FS, period=N, oversampling=10, fit_oversampling=5, black_box=False)
EFFECTS = ["cubic_stiffness", "quadratic_damping", "recalibration"]


def _db(x):
    return 10 * np.log10(x)


def _data(n_periods, seed=0, f_band=(5.0, 150.0)):
    """Two training realisations of ``n_periods`` periods, a validation
    period and a sweep from rest, through the softening structure; also the
    noise actually added to the training outputs."""
    X, _ = multisine(N, fs=FS, f_band=f_band, rms=50.0, n_periods=n_periods, n_realizations=3,
                     random_state=seed)
    sweep = linear_chirp(np.arange(3000) / FS, f_start=15.0, rate=8.0, amplitude=10.0)
    train = SignalSet.from_signals([x[:, 0] for x in X[:2]], N, FS, 10)
    val = SignalSet.from_signals([X[2, :N, 0], sweep], N, FS, 10)
    rng = np.random.RandomState(seed)
    y_train = simulate_signals(REAL, train, noise_rms=NOISE_RMS, random_state=rng)
    y_val = simulate_signals(REAL, val, noise_rms=NOISE_RMS, random_state=rng)
    added = np.concatenate([a - b for a, b in zip(y_train, simulate_signals(REAL, train))])
    return train.u, y_train, val.u, y_val, float(np.mean(added**2))


@pytest.fixture(scope="module")
def single_periods():
    u, y, u_val, y_val, noise_var = _data(n_periods=1)
    diag = GapDiagnosis(NOMINAL, effects=EFFECTS, **FAST).fit(u, y)
    return diag, diag.report(u_val, y_val), noise_var


def test_single_periods_name_the_cubic_stiffness(single_periods):
    """The issue's case: cubic_stiffness, closing the whole gap, where the
    verdict used to be "unexplained" (closure 85 % against a floor guessed
    60 dB under the gap)."""
    diag, report, noise_var = single_periods
    assert report.best_effect == "cubic_stiffness" and report.explained
    best = report.ranking[0]
    assert best.name == "cubic_stiffness"
    assert best.params["k3"] == pytest.approx(-1e8, rel=0.01)
    assert best.closure > 0.99
    # measured: -62.6 dB -> -114.7 dB, noise added -114.7 dB, floor -114.4 dB
    assert report.gap_db > -64 and best.gap_after_db < _db(noise_var) + 0.5
    assert abs(report.noise_floor_db - _db(noise_var)) < 1.0
    assert report.significant and report.p_value < 1e-10


def test_single_periods_report_names_the_noise_estimate(single_periods):
    diag, report, _ = single_periods
    assert diag.noise_.source == "non_excited_lines" and diag.noise_.upper_bound
    assert report.noise_source == "non_excited_lines"
    text = str(report)
    assert "nan" not in text
    assert ("noise: residual of the cubic_stiffness model at the 616 DFT lines the input does not excite "
            "(an upper bound; no period repeated)") in text
    d = report.to_dict()
    assert d["noise_source"] == "non_excited_lines" and "cubic_stiffness" in d["noise_detail"]


def test_clean_periodic_case_keeps_its_floor_and_verdict():
    """Two periods per signal: the floor is still the period-to-period
    spread (the same numbers as before), and the report says so."""
    u, y, u_val, y_val, noise_var = _data(n_periods=2)
    diag = GapDiagnosis(NOMINAL, effects=EFFECTS, **FAST).fit(u, y)
    expected = estimate_noise(y, N)
    assert diag.noise_.source == "periods" and not diag.noise_.upper_bound
    assert diag.noise_.variance == expected.variance
    np.testing.assert_array_equal(diag.noise_.spectrum, expected.spectrum)
    report = diag.report(u_val, y_val)
    assert report.best_effect == "cubic_stiffness"
    assert report.ranking[0].closure > 0.99
    assert "noise: spread over the periods of 2 training signals (2 periods)" in str(report)


def test_every_line_excited_and_no_black_box_says_there_is_no_floor():
    """A multisine over the whole band leaves no line free of input, and
    without a black box nothing else gives a floor: the report says so,
    rather than "noise floor nan dB"."""
    u, y, u_val, y_val, _ = _data(n_periods=1, f_band=(FS / N, FS / 2))
    diag = GapDiagnosis(NOMINAL, effects=["cubic_stiffness"], **FAST).fit(u, y)
    assert diag.noise_ is None
    report = diag.report(u_val, y_val)
    text = str(report)
    assert "no noise floor" in text and "nan" not in text
    assert "no noise estimate (no period repeated, no input repeated, no line free of input)" in text
    assert report.noise_source is None


# -- the estimates, one by one ----------------------------------------------


def _white(n, rms, rng):
    return rms * rng.standard_normal(n)


@pytest.fixture(scope="module")
def one_period_records():
    """Two one-period multisines (5-150 Hz) through the nominal, with white
    noise of 1 um, and the noise itself."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=1, n_realizations=2, random_state=1)
    u = [x[:, 0] for x in X]
    clean = simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))
    rng = np.random.RandomState(1)
    noise = [_white(N, 1e-6, rng) for _ in u]
    return u, clean, [c + e for c, e in zip(clean, noise)], float(np.mean(np.concatenate(noise) ** 2))


def test_non_excited_lines_give_the_white_noise_level(one_period_records):
    """The exact model's residual at the 616 lines above the band (the 12
    below it are too few for a band of their own) is the noise: its level within 0.5 dB; a model off by a gain of 1 %
    leaves nothing there either (its error sits on the excited lines), one
    with a harmonic leaves it at the free lines and is not chosen."""
    u, clean, y, noise_var = one_period_records
    harmonic = [c + 1e-5 * np.cos(2 * np.pi * 250 * np.arange(N) / N) for c in clean]
    floor = non_excited_noise(u, y, {"harmonic": harmonic, "exact": clean}, N, FS)
    assert floor.source == "non_excited_lines" and floor.upper_bound and not floor.replicated
    assert "exact model at the 616 DFT lines" in floor.detail
    assert abs(_db(floor.variance) - _db(noise_var)) < 0.5
    assert floor.spectrum.shape == (N // 2 + 1,)
    assert floor.dof_per_sample > 0.95  # white: about one per sample
    gain = non_excited_noise(u, y, {"gain": [1.01 * c for c in clean]}, N, FS)
    assert abs(_db(gain.variance) - _db(noise_var)) < 0.5
    only_harmonic = non_excited_noise(u, y, {"harmonic": harmonic}, N, FS)
    assert _db(only_harmonic.variance) > _db(noise_var) + 10  # an upper bound indeed


def test_non_excited_lines_follow_a_roll_off(one_period_records):
    """Noise low-passed above 260 Hz (an anti-alias filter): the floor keeps
    the in-band level (extended from the free lines just above the band)
    instead of averaging the roll-off into it.  That level comes from the
    38 free lines of 150-164 Hz: a spread of 0.7 dB (measured: +1.2 dB)."""
    u, clean, _, _ = one_period_records
    rng = np.random.RandomState(2)
    noise = []
    for _ in u:
        spec = np.fft.rfft(_white(N, 1e-6, rng))
        spec[np.fft.rfftfreq(N, 1 / FS) > 260.0] *= 0.1
        noise.append(np.fft.irfft(spec, N))
    y = [c + e for c, e in zip(clean, noise)]
    floor = non_excited_noise(u, y, {"exact": clean}, N, FS)
    f = np.fft.rfftfreq(N, 1 / FS)
    assert abs(_db(np.mean(floor.spectrum[(f > 5) & (f < 150)])) - _db(1e-12)) < 1.5
    assert abs(_db(np.mean(floor.spectrum[f > 280])) - _db(1e-14)) < 1.5
    # the variance follows the in-band level (measured: +0.8 dB)
    assert abs(_db(floor.variance) - _db(np.mean(np.concatenate(noise) ** 2))) < 1.0


def test_non_excited_lines_of_records_that_are_not_periodic():
    """Band-limited noise records (5-150 Hz, 4,000 samples, from rest): read
    through a rectangular window the input's leak covers every line, and the
    diagnosis had no floor at all (issue 16, family c: the true cubic spring
    closed "only 81 %" against a floor guessed 60 dB below the gap).  Read
    through a Hann window, the exact model's residual above the band gives
    the white noise's level within 0.5 dB."""
    from scipy.signal import butter, sosfiltfilt

    rng = np.random.RandomState(4)
    sos = butter(6, [5.0, 150.0], btype="band", fs=FS, output="sos")
    u = []
    for _ in range(2):
        e = sosfiltfilt(sos, rng.standard_normal(4000))
        u.append(50.0 * e / np.std(e))
    records = SignalSet.from_signals(u, N, FS, 10)  # 4,000 samples: not periodic, from rest
    clean = simulate_signals(NOMINAL, records)
    noise = [_white(4000, 1e-6, rng) for _ in u]
    y = [c + e for c, e in zip(clean, noise)]
    floor = non_excited_noise(u, y, {"nominal": clean}, N, FS)
    assert floor is not None and floor.source == "non_excited_lines"
    assert abs(_db(floor.variance) - _db(np.mean(np.concatenate(noise) ** 2))) < 0.5
    # without the window (the records taken as periodic) hardly a line is free
    lines = [np.abs(np.fft.rfft(x)) ** 2 for x in u]
    assert max(np.sum(p < 1e-6 * p[1:].max()) for p in lines) < 20


def test_non_excited_lines_of_a_ramp_of_joined_realisations():
    """Four multisine realisations in a row under a growing amplitude, the
    way family c's ramp is recorded (issue 16): the jumps where realisations
    join leak over every line of a window that spans the record, and the
    Coulomb-friction case of the benchmark's first seed lost its floor
    (closure 46 %, "unexplained"; 100 % with it).  Read in Hann segments of
    ``NOISE_SEGMENT`` samples, the segments without a jump keep their lines
    and the exact model's residual gives the white noise's level within
    0.5 dB."""
    from sklearn_pnlss.gap.verdict.noise_floor import NOISE_SEGMENT, _power

    X, _ = multisine(8192, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=1, n_realizations=4, random_state=0)
    n = 4 * 8192 - 192  # no whole number of periods: not periodic
    ramp = np.concatenate([x[:, 0] for x in X])[:n] * np.linspace(0.0, 1.0, n)
    u = [50.0 * ramp / np.std(ramp)]
    records = SignalSet.from_signals(u, N, FS, 10)
    clean = simulate_signals(NOMINAL, records)
    rng = np.random.RandomState(3)
    noise = [_white(n, 1e-6, rng)]
    y = [c + e for c, e in zip(clean, noise)]
    whole = _power(u[0], np.hanning(n))
    assert np.sum(whole < 1e-6 * whole[1:].max()) < 20  # one window: hardly a line is free
    floor = non_excited_noise(u, y, {"nominal": clean}, N, FS)
    assert n > 7 * NOISE_SEGMENT and floor is not None and floor.source == "non_excited_lines"
    assert f"segments of {NOISE_SEGMENT} samples" in floor.detail
    assert abs(_db(floor.variance) - _db(np.mean(noise[0] ** 2))) < 0.5


def test_records_with_zero_input_gaps_are_read_through_one_window():
    """Segments are the fallback, not the rule: realisations separated by
    zero-input gaps leave free lines through one window, and read in
    segments the gaps' ringing brought the harmonics a wrong model leaves
    into the floor (hysteresis removed from the candidates, benchmark
    family c seed 501: -82.2 dB instead of the noise's -102.8 dB, and
    quadratic damping named).  Through one window the exact model gives
    the noise's level within 0.5 dB."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=1, n_realizations=4, random_state=5)
    gap = np.zeros(300)
    u = [np.concatenate([np.concatenate([x[:, 0], gap]) for x in X])]  # 5,296 samples: not periodic
    records = SignalSet.from_signals(u, N, FS, 10)
    clean = simulate_signals(NOMINAL, records)
    rng = np.random.RandomState(5)
    noise = [_white(u[0].size, 1e-6, rng)]
    floor = non_excited_noise(u, [c + e for c, e in zip(clean, noise)], {"nominal": clean}, N, FS)
    assert floor is not None and "segments" not in floor.detail
    assert abs(_db(floor.variance) - _db(np.mean(noise[0] ** 2))) < 0.5


def test_no_free_lines_no_estimate(one_period_records):
    X, _ = multisine(N, fs=FS, f_band=(FS / N, FS / 2), rms=50.0, n_periods=1, n_realizations=1, random_state=0)
    u = [X[0, :, 0]]
    y = simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))
    assert non_excited_noise(u, y, {"nominal": y}, N, FS) is None


def test_repeated_inputs_give_the_noise(one_period_records):
    """The same realisation run twice: half the output difference is the
    noise, at every line; different realisations give no estimate."""
    u, clean, _, _ = one_period_records
    rng = np.random.RandomState(3)
    noise = [_white(N, 1e-6, rng) for _ in range(2)]
    floor = repeated_input_noise([u[0], u[0].copy()], [clean[0] + noise[0], clean[0] + noise[1]], N, FS)
    assert floor.source == "repeated_inputs" and floor.replicated and not floor.upper_bound
    assert "1 pair" in floor.detail
    assert abs(_db(floor.variance) - _db(1e-12)) < 0.5
    assert repeated_input_noise(u, clean, N, FS) is None


def test_residual_noise_is_the_smallest_signal_misfit():
    y = [np.zeros(100), np.zeros(200)]
    floor = residual_noise(y, [np.full(100, 2e-6), np.full(200, 1e-6)], 64)
    assert floor.variance == pytest.approx(1e-12)
    assert floor.source == "black_box_residual" and floor.upper_bound
    assert floor.spectrum.shape == (33,)
    assert residual_noise(y, [None, np.zeros(200)], 64) is None


# -- the verdict against an estimated floor -----------------------------------

S2 = 1e-12
SIZE = 100_000


def _fit(name, n_params=1, recalibration=False):
    effect = stub_effect(name, n_params, recalibration)
    return EffectFit(effect, np.zeros(n_params), {}, train_mse=S2, n_evaluations=1, converged=True, message="")


def _decide(closure, bb_closure, source):
    """One signal 40 dB above the floor; a candidate and the black box
    leaving the given shares of it."""
    noise = NoiseFloor(S2, np.full(513, S2), 1.0, source=source, detail=source)

    def after(c):
        return np.full(SIZE, np.sqrt(S2 * 10 ** ((1 - c) * 4)))

    return decide([_fit("c")], [np.zeros(SIZE)], [np.full(SIZE, 1e-4)], [[after(closure)]],
                  [after(bb_closure)], noise, 1e-3)


def test_as_much_as_a_good_black_box_is_explained_when_the_floor_is_estimated():
    """Against an estimated floor a candidate closing 85 % is explained when
    the black box closes 86 % (both stop where the floor estimate is off);
    against the period-to-period floor (exact) it is not."""
    assert SETTINGS.explained_closure == 0.9 and SETTINGS.black_box_min_closure == 0.8
    d = _decide(0.85, 0.86, "non_excited_lines")
    assert d.best_effect == "c" and d.explained
    assert "as much as the black box (86 %)" in d.reason
    assert d.noise_source == "non_excited_lines"
    assert _decide(0.85, 0.86, "periods").best_effect == "unexplained"
    # a black box closing 55 % is no yardstick (a second mode withheld, one
    # period per signal, measured: recalibration 67 %, black box 53 %)
    assert _decide(0.67, 0.55, "non_excited_lines").best_effect == "unexplained"
    # a candidate far below the black box stays unexplained
    assert _decide(0.5, 0.95, "non_excited_lines").best_effect == "unexplained"


def test_unsettled_signals_are_those_whose_periods_differ_far_more():
    rng = np.random.RandomState(0)
    base = np.sin(2 * np.pi * 3 * np.arange(N) / N)
    drift = np.linspace(0, 0.01, 4)[:, None] * base  # common to every signal: not unsettled
    signals = [(np.tile(base, (4, 1)) * (k + 1) + drift + 1e-4 * rng.standard_normal((4, N))).ravel()
               for k in range(4)]
    assert unsettled_signals(signals, N) == []
    # realisation 2's periods differ as a chaotic response's do
    signals[2] = signals[2] + 1e-2 * rng.standard_normal(4 * N)
    assert unsettled_signals(signals, N) == [2]
    # three of four chaotic: the settled one is the reference
    chaotic = [y + 1e-2 * rng.standard_normal(4 * N) if k else y for k, y in enumerate(signals)]
    assert unsettled_signals(chaotic, N) == [1, 2, 3]
    # one signal of several periods has nothing to compare with
    assert unsettled_signals(signals[2:3] + [base], N) == []
    assert unsettled_signals(signals, None) == []
