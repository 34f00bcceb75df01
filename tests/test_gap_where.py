"""The "where" analysis of the gap diagnosis (sklearn_pnlss.gap.where).

Each test injects a gap of known size at a known place (frequency band,
amplitude, time window, period-to-period drift, force law) on top of a
nominal simulation, and checks that the analysis puts it there, with the
right number of dB.
"""
import numpy as np
import pytest

from sklearn_pnlss.gap.verdict.noise_floor import NoiseFloor, estimate_noise
from sklearn_pnlss.gap.fitting.simulate import SignalSet, simulate_signals
from sklearn_pnlss.gap.readings import content_limit, missing_force, signal_derivative
from sklearn_pnlss.gap.where import locate_gap
from sklearn_pnlss.physics import BoucWen, Oscillator
from sklearn_pnlss.signals import linear_chirp, multisine

FS, N = 750.0, 1024
NOMINAL = Oscillator(2.0, 10.0, 5e4)


def _where(u, y, y_nominal, n_periods, *, noise=None, train=None):
    """locate_gap on validation signals; the training set defaults to them."""
    u_train, y_train, y_train_nominal = train if train is not None else (u, y, y_nominal)
    return locate_gap(NOMINAL, u, y, y_nominal, n_periods, fs=FS, period=N, noise=noise,
                      significance=1e-3, u_train=u_train, y_train=y_train, y_train_nominal=y_train_nominal)


@pytest.fixture(scope="module")
def noisy_multisines():
    """Three two-period multisines through the nominal, with 1 um white
    noise: two train (and give the noise floor), one validates."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=50.0, n_periods=2, n_realizations=3, random_state=0)
    u = [x[:, 0] for x in X]
    y_nominal = simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))
    rng = np.random.RandomState(0)
    y = [s + 1e-6 * rng.standard_normal(s.size) for s in y_nominal]
    return u, y, y_nominal, estimate_noise(y[:2], N)


def _tones(bins, amplitude, n_samples):
    """Cosines on DFT bins of the period N, each of the given amplitude."""
    n = np.arange(n_samples)
    return sum(amplitude * np.cos(2 * np.pi * k * n / N + k) for k in bins)


def test_gap_on_excited_lines_is_found_in_its_band(noisy_multisines):
    """21 tones of 2 um on bins 70-90 (51-66 Hz): the band holding them is
    the worst, all 21 lines are significant, and the band's gap power is
    the tones' power, N A^2 / 4 per line in the unitary DFT (-76.67 dB)."""
    u, y, y_nominal, noise = noisy_multisines
    bins = np.arange(70, 91)
    gap = _tones(bins, 2e-6, 2 * N)
    freq = _where([u[2]], [y[2] + gap], [y_nominal[2]], [2], noise=noise,
                  train=(u[:2], y[:2], y_nominal[:2])).frequency
    # A 5-150 Hz input: harmonics up to 450 Hz, capped at 0.4 fs = 300 Hz.
    assert freq.bands[-1].f_hi == pytest.approx(300.0)
    assert len(freq.bands) == 8
    worst = max(freq.bands, key=lambda b: b.gap_db - b.noise_db)
    assert (worst.f_lo, worst.f_hi) == (37.5, 75.0)
    assert worst.gap_db == pytest.approx(10 * np.log10(bins.size * 4e-12 * N / 4), abs=0.05)
    assert worst.gap_db - worst.noise_db > 25
    assert freq.significant[bins].all()
    assert freq.line_kind[bins].tolist() == [1] * bins.size  # excited lines
    # Elsewhere the gap is the noise: within 2 dB of the floor in every band.
    for band in freq.bands:
        if band is not worst:
            assert abs(band.gap_db - band.noise_db) < 2.0, band
    # The per-line test compares each line with a floor estimated from two
    # periods of two signals, so a few lines outside the tones pass it too
    # (measured: 7 of 491); the tones stand out nonetheless.
    others = np.setdiff1d(np.arange(1, freq.significant.size), bins)
    assert freq.significant[others].mean() < 0.05


def test_gap_on_even_lines_shows_as_even_distortion(noisy_multisines):
    """Tones on even bins above the excited band (the output of an even
    nonlinearity) count as significant even, not excited, lines."""
    u, y, y_nominal, noise = noisy_multisines
    bins = np.arange(280, 301, 2)  # 205-220 Hz, even, not excited
    freq = _where([u[2]], [y[2] + _tones(bins, 2e-6, 2 * N)], [y_nominal[2]], [2], noise=noise,
                  train=(u[:2], y[:2], y_nominal[:2])).frequency
    assert freq.detection_lines
    kinds = freq.line_kinds
    assert kinds["even_not_excited"].n_significant >= bins.size
    assert kinds["even_not_excited"].gap_db - kinds["even_not_excited"].noise_db > 20
    # the odd lines hold noise only
    assert abs(kinds["odd_not_excited"].gap_db - kinds["odd_not_excited"].noise_db) < 2.0
    assert (freq.line_kind[bins] == 3).all()


def test_no_frequency_analysis_without_noise_floor_or_periodic_signal(noisy_multisines):
    u, y, y_nominal, noise = noisy_multisines
    assert _where([u[2]], [y[2]], [y_nominal[2]], [2], noise=None).frequency is None
    assert _where([u[2]], [y[2]], [y_nominal[2]], [0], noise=noise,
                  train=(u[:2], y[:2], y_nominal[:2])).frequency is None


@pytest.fixture(scope="module")
def three_levels():
    """One multisine realisation at 25, 50 and 100 N rms through the linear
    nominal: the responses are exact scalings of each other."""
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=1.0, n_periods=2, n_realizations=1, random_state=1)
    u = [level * X[0, :, 0] for level in (25.0, 50.0, 100.0)]
    return u, simulate_signals(NOMINAL, SignalSet.from_signals(u, N, FS, 10))


def test_relative_gap_against_input_level(three_levels):
    """A gain error 1e-3 is a relative gap of 20 log10(1e-3 / 1.001) dB at
    every level; a cubic error grows by 40 log10(2) = 12.04 dB per doubling
    of the level (error ~ level^3 against output ~ level), once the error
    is small enough not to change the output's power."""
    u, y_nominal = three_levels
    scale = np.sqrt(np.mean(y_nominal[1] ** 2))
    for law, expected_step in ((lambda s: 1e-3 * s, 0.0), (lambda s: 1e-5 * s**3 / scale**2, 40 * np.log10(2))):
        y = [s + law(s) for s in y_nominal]
        amp = _where(u[2:], y[2:], y_nominal[2:], [2], train=(u[:2], y[:2], y_nominal[:2])).amplitude
        levels = amp.input_levels
        assert [lv.set for lv in levels] == ["train", "train", "validation"]
        assert [lv.input_rms for lv in levels] == pytest.approx([25.0, 50.0, 100.0])
        assert amp.several_levels
        db = np.array([lv.relative_gap_db for lv in levels])
        np.testing.assert_allclose(np.diff(db), expected_step, atol=2e-3)
    # the gain error's level, exactly
    y = [1.001 * s for s in y_nominal]
    amp = _where(u, y, y_nominal, [2, 2, 2]).amplitude
    assert amp.input_levels[0].relative_gap_db == pytest.approx(20 * np.log10(1e-3 / 1.001), abs=1e-6)


def test_displacement_driven_gap_rises_with_displacement_not_velocity(three_levels):
    """A cubic error of the displacement: its gap climbs over the
    displacement bins (every bin above the last, as y^6 would) but barely
    changes over the velocity bins."""
    u, y_nominal = three_levels
    scale = np.sqrt(np.mean(y_nominal[2] ** 2))
    y = [s + 1e-3 * s**3 / scale**2 for s in y_nominal]
    amp = _where(u[2:], y[2:], y_nominal[2:], [2]).amplitude
    assert amp.displacement.noise_db is None  # no noise floor given
    disp = np.array([b.gap_db for b in amp.displacement.bins])
    vel = np.array([b.gap_db for b in amp.velocity.bins])
    assert np.all(np.diff(disp) > 0)
    assert disp[-1] - disp[0] > 50  # measured: 74 dB
    assert np.ptp(vel) < 15  # measured: 9 dB
    edges = [b.hi for b in amp.displacement.bins]
    assert edges[-1] == pytest.approx(np.max(np.abs(y[2])))


def test_gap_in_a_time_window_of_a_sweep():
    """A 10 um offset over samples 1500-1800 of a 15 Hz + 8 Hz/s sweep from
    rest: exactly the four 75-sample windows that cover it show -100 dB, the
    others none, and each window reads the sweep's frequency 15 + 8 t."""
    t = np.arange(3000) / FS
    sweep = linear_chirp(t, f_start=15.0, rate=8.0, amplitude=10.0)
    y_nominal = simulate_signals(NOMINAL, SignalSet.from_signals([sweep], N, FS, 10))[0]
    offset = np.zeros(t.size)
    offset[1500:1800] = 1e-5
    time = _where([sweep], [y_nominal + offset], [y_nominal], [0]).time
    windows = time.sweeps[0].windows
    assert len(windows) == 40
    gap_db = np.array([w.gap_db for w in windows])
    hit = np.flatnonzero(gap_db > -1000)
    assert hit.tolist() == [20, 21, 22, 23]
    np.testing.assert_allclose(gap_db[hit], -100.0, atol=1e-9)
    centres = np.array([w.t for w in windows])
    np.testing.assert_allclose(centres, (np.arange(40) + 0.5) * 75 / FS)
    freq = np.array([w.frequency for w in windows])
    np.testing.assert_allclose(freq[1:-1], 15.0 + 8.0 * centres[1:-1], atol=0.2)
    assert time.drift is None  # the training signals have two periods


def test_drift_from_period_to_period():
    """Training responses whose period p is shifted by p d: the change from
    the first period over twice the noise variance is p^2 |d|^2 / (2 s^2),
    period by period; without the shift it stays at the noise level."""
    P, s2 = 5, 1e-12
    noise = NoiseFloor(variance=s2, spectrum=np.full(N // 2 + 1, s2), dof_per_sample=1.0)
    rng = np.random.RandomState(0)
    u = [rng.standard_normal(P * N) for _ in range(2)]
    base = [np.tile(rng.standard_normal(N) * 1e-4, P) for _ in range(2)]
    d = 3e-6 * rng.standard_normal(N)
    shift = np.concatenate([p * d for p in range(P)])
    drift = _where(u, [b + shift for b in base], base, [P, P], noise=noise).time.drift
    expected = [10 * np.log10(p**2 * np.mean(d**2) / (2 * s2)) for p in range(1, P)]
    np.testing.assert_allclose(drift.change_vs_noise_db, expected, atol=1e-9)
    assert drift.drifting
    ratios = np.array([p**2 * np.mean(d**2) / (2 * s2) for p in range(1, P)])
    assert drift.slope_per_period == pytest.approx(np.polyfit(np.arange(1, P), ratios, 1)[0])
    # noise alone: the change between periods is 2 s^2, the ratio about 1
    still = [b + np.sqrt(s2) * rng.standard_normal(b.size) for b in base]
    drift = _where(u, still, base, [P, P], noise=noise).time.drift
    np.testing.assert_allclose(drift.change_vs_noise_db, 0.0, atol=0.3)
    assert not drift.drifting


def test_signal_derivative_is_exact_on_periodic_tones():
    """The DFT derivative of a periodic tone is exact; with ``f_max`` below
    a tone, that tone is dropped."""
    n = np.arange(N)
    w1, w2 = 2 * np.pi * 10 * FS / N, 2 * np.pi * 200 * FS / N
    y = np.sin(w1 * n / FS) + 0.1 * np.sin(w2 * n / FS)
    v = signal_derivative(y, FS, 1, N)
    np.testing.assert_allclose(v, w1 * np.cos(w1 * n / FS) + 0.1 * w2 * np.cos(w2 * n / FS), atol=1e-9 * w2)
    a = signal_derivative(y, FS, 1, N, order=2, f_max=100.0)
    np.testing.assert_allclose(a, -(w1**2) * np.sin(w1 * n / FS), atol=1e-9 * w1**2)


def test_content_limit_is_three_times_the_input_band():
    X, _ = multisine(N, fs=FS, f_band=(5.0, 60.0), rms=1.0, random_state=0)
    assert content_limit([X[0, :, 0]], FS) == pytest.approx(3 * 60.0, abs=3 * FS / N)
    X, _ = multisine(N, fs=FS, f_band=(5.0, 150.0), rms=1.0, random_state=0)
    assert content_limit([X[0, :, 0]], FS) == pytest.approx(0.4 * FS)


def test_missing_force_of_a_stiffness_error(noisy_multisines):
    """Measured on a structure 10 % stiffer than the nominal, the force the
    nominal leaves unbalanced is 5000 N/m times the displacement, and the
    map over the (displacement, velocity) plane holds that law cell by
    cell."""
    u, _, _, _ = noisy_multisines
    real = Oscillator(2.0, 10.0, 5.5e4)
    y = simulate_signals(real, SignalSet.from_signals(u, N, FS, 20))
    y_disp, _, _, force = missing_force(NOMINAL, u, y, [2, 2, 2], N, FS, content_limit(u, FS))
    assert y_disp.size == 3 * N  # periods averaged, one per signal
    slope = np.polyfit(y_disp, force, 1)[0]
    assert slope == pytest.approx(5e3, rel=0.01)
    fmap = _where(u, y, y, [2, 2, 2]).state_plane
    assert not fmap.stateful_nominal_left_out
    centres = 0.5 * (fmap.displacement_edges[1:] + fmap.displacement_edges[:-1])
    rows = np.isfinite(fmap.force).any(axis=1)
    mean_force = np.nanmean(fmap.force[rows], axis=1)
    assert np.polyfit(centres[rows], mean_force, 1)[0] == pytest.approx(5e3, rel=0.05)
    assert np.all(fmap.count[np.isfinite(fmap.force)] >= 20)


def test_stateful_nominal_elements_are_flagged():
    """A hysteretic nominal element carries states that are not measured:
    the missing-force map leaves it out and says so."""
    nominal = NOMINAL.with_forces([BoucWen()])
    X, _ = multisine(N, fs=FS, rms=50.0, n_periods=1, random_state=0)
    u = [X[0, :, 0]]
    y = simulate_signals(nominal, SignalSet.from_signals(u, N, FS, 10))
    where = locate_gap(nominal, u, y, y, [1], fs=FS, period=N, noise=None, significance=1e-3,
                       u_train=u, y_train=y, y_train_nominal=y)
    assert where.state_plane.stateful_nominal_left_out
