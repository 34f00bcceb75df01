"""BLAEstimator on systems whose truth is known: parameters recovered,
noise and distortion levels measured, odd/even nonlinearity detected."""
import pickle

import numpy as np
import pytest
import scipy.signal as ss
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV, KFold, cross_val_score

from sklearn_pnlss import BLAEstimator
from sklearn_pnlss.metrics import rms_db_scorer, rms_error
from sklearn_pnlss.signals import multisine
from sklearn_pnlss.statespace.linear import simulate_linear, simulate_linear_signal

FS = 750.0
N = 1024
# A lightly damped mode like the Bouc-Wen benchmark's: 25.16 Hz, 1.58 %.
M, C, K = 2.0, 10.0, 5e4
F_TRUE = np.sqrt(K / M) / (2 * np.pi)  # undamped natural frequency
ZETA_TRUE = C / (2 * np.sqrt(K * M))
SYS = ss.StateSpace([[0, 1], [-K / M, -C / M]], [[0], [1 / M]], [[1, 0]], [[0]]).to_discrete(1 / FS)


def steady_state_output(X, static=lambda y: y, noise_std=0.0, seed=0):
    """Simulate the linear mode in steady state, pass its output through a
    static nonlinearity and add white noise."""
    rng = np.random.default_rng(seed)
    Y = []
    for x in X:
        y = simulate_linear_signal(SYS.A, SYS.B, SYS.C, SYS.D, x, periodic_with=N)
        Y.append(static(y) + noise_std * rng.standard_normal(y.shape))
    return np.stack(Y)


@pytest.fixture(scope="module")
def linear_data():
    X, lines = multisine(N, fs=FS, f_band=(5, 150), rms=50, n_periods=4, n_realizations=3, random_state=0)
    y_clean = steady_state_output(X)
    noise = 1e-3 * y_clean.std()
    return X, steady_state_output(X, noise_std=noise), lines, noise


def test_linear_system_recovered(linear_data):
    X, y, lines, noise = linear_data
    model = BLAEstimator(n_states=2, period=N, fs=FS).fit(X, y)
    np.testing.assert_array_equal(model.lines_, lines)
    assert model.natural_frequencies_[0] == pytest.approx(F_TRUE, rel=1e-4)
    assert model.damping_ratios_[0] == pytest.approx(ZETA_TRUE, rel=1e-2)
    assert model.n_params_ == 2 * 2 + 2 + 2 + 1
    # Simulation error is at the noise level (white noise std `noise`).
    assert rms_error(y, model.predict(X)) == pytest.approx(noise, rel=0.05)


def test_noise_variance_matches_truth(linear_data):
    X, y, lines, noise = linear_data
    model = BLAEstimator(n_states=2, period=N, fs=FS).fit(X, y)
    # White noise of std s gives a DFT variance N s^2 per period; averaged
    # over P periods and R realisations and divided by |U|^2.
    U = np.fft.rfft(X[0, :N, 0])[lines]
    expected = N * noise**2 / (4 * 3) / np.abs(U) ** 2
    ratio = np.median(model.frf_var_noise_[:, 0, 0] / expected)
    assert ratio == pytest.approx(1.0, rel=0.15)
    # A linear system: the spread over realisations is noise only.
    assert np.median(model.frf_var_total_ / model.frf_var_noise_) == pytest.approx(1.0, rel=0.5)


def test_nonlinear_distortion_detected_odd_vs_even():
    X, lines = multisine(N, fs=FS, f_band=(5, 150), rms=50, kind="random_odd", n_periods=2,
                         n_realizations=4, random_state=1)
    y_lin = steady_state_output(X)
    s = y_lin.std()
    odd = BLAEstimator(n_states=2, period=N, fs=FS).fit(
        X, steady_state_output(X, lambda y: y + 0.2 * y**3 / s**2, noise_std=1e-4 * s))
    even = BLAEstimator(n_states=2, period=N, fs=FS).fit(
        X, steady_state_output(X, lambda y: y + 0.2 * y**2 / s, noise_std=1e-4 * s))
    lv_odd, lv_even = odd.distortion_levels_, even.distortion_levels_
    # Odd nonlinearity: odd detection lines far above even ones and noise.
    assert lv_odd["odd"] > lv_odd["even"] + 20
    assert lv_odd["odd"] > lv_odd["noise"] + 30
    # Even nonlinearity: the reverse.
    assert lv_even["even"] > lv_even["odd"] + 20
    # Stochastic nonlinear distortion dominates the noise on the FRF.
    assert np.median(odd.frf_var_nonlinear_ / odd.frf_var_noise_) > 100


def test_welch_estimate_from_random_excitation():
    rng = np.random.default_rng(3)
    X = rng.standard_normal((2, 20000, 1)) * 50
    y = np.stack([simulate_linear(SYS.A, SYS.B, SYS.C, SYS.D, x)[0] for x in X])
    model = BLAEstimator(n_states=2, fs=FS).fit(X, y)
    assert model.natural_frequencies_[0] == pytest.approx(F_TRUE, rel=2e-3)


def test_periodic_and_transient_signals_scored_in_one_call(linear_data):
    X, y, _, _ = linear_data
    model = BLAEstimator(n_states=2, period=N, fs=FS).fit(X, y)
    u_rest = X[0, : N + 100]  # not a multiple of the period: starts from rest
    y_rest = simulate_linear(SYS.A, SYS.B, SYS.C, SYS.D, u_rest)[0]
    pred = model.predict([X[0, :N], u_rest])
    assert isinstance(pred, list) and pred[1].shape == (N + 100, 1)
    assert rms_error(y_rest, pred[1]) < 1e-3 * y_rest.std()
    assert rms_error(y[0, :N], pred[0]) < 2e-3 * y_rest.std()


def test_clone_pickle_and_grid_search_split_whole_signals(linear_data):
    X, y, _, _ = linear_data
    model = BLAEstimator(n_states=2, period=N, fs=FS)
    fitted = clone(model).fit(X, y)
    again = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(again.predict(X), fitted.predict(X))
    scores = cross_val_score(model, X, y, cv=KFold(3), scoring=rms_db_scorer)
    assert scores.shape == (3,) and np.all(scores > 50)
    search = GridSearchCV(model, {"n_states": [1, 2, 4]}, cv=KFold(3), scoring=rms_db_scorer).fit(X, y)
    assert search.best_params_["n_states"] in (2, 4)
    assert search.cv_results_["mean_test_score"][0] < search.best_score_ - 10


@pytest.mark.parametrize(
    "kwargs, X_shape, match",
    [
        ({"period": 1000}, (2, 2048, 1), "not a multiple of period=1000"),
        ({"period": N, "lines": [0, 3]}, (2, 2 * N, 1), "lines must be DFT bins"),
    ],
)
def test_bad_arguments_name_the_fix(kwargs, X_shape, match):
    X = np.random.default_rng(0).standard_normal(X_shape)
    with pytest.raises(ValueError, match=match):
        BLAEstimator(**kwargs).fit(X, X)


def test_mimo_needs_blocks_of_experiments():
    X = np.random.default_rng(0).standard_normal((3, 2 * N, 2))
    with pytest.raises(ValueError, match="multiple of 2"):
        BLAEstimator(period=N).fit(X, X[..., :1])


def test_line_detection_sets_aside_hum_and_leakage(linear_data):
    """A measured input adds bins far below the multisine's lines (mains hum,
    leakage): within -60 dB of the strongest line, yet with almost none of the
    power. They are not excited lines; a designed level spread is kept."""
    from sklearn_pnlss.frequency.bla import excited_lines

    X, y, lines, _ = linear_data
    t = np.arange(X.shape[1]) / FS
    # 50 Hz is bin 50 * N / FS = 68.3: leaks into its neighbours at about -40 dB.
    hum = 0.02 * 50 * np.sin(2 * np.pi * 50.0 * t) + 0.01 * 50 * np.sin(2 * np.pi * 150.0 * t)
    X_hum = X + hum[None, :, None]
    U = np.fft.rfft(X_hum.reshape(3, 4, N, 1).mean(axis=1), axis=1)
    assert excited_lines(U).size > lines.size  # the plain -60 dB threshold takes the hum
    np.testing.assert_array_equal(excited_lines(U, gap_db=20.0), lines)
    model = BLAEstimator(n_states=2, period=N, fs=FS).fit(X_hum, y)
    np.testing.assert_array_equal(model.lines_, lines)
    # Two designed levels 10 dB apart, each with a real share of the power: kept.
    spec = np.zeros((1, N // 2 + 1, 1), dtype=complex)
    spec[0, 10:20, 0] = 1.0
    spec[0, 20:30, 0] = 10 ** (-10 / 20)
    spec[0, 40, 0] = 1e-3  # -60 dB + : a stray bin, set aside
    np.testing.assert_array_equal(excited_lines(spec, gap_db=20.0), np.arange(10, 30))
    # a lower group 20.5 dB down but with 3 % of the power is kept
    spec[0, 40:400, 0] = 0.03
    assert excited_lines(spec, gap_db=20.0).size == 20 + 360
