"""Nonparametric frequency analysis (``frequency/bla.py``, ``frequency/noise.py``)
checked against numbers known in closed form.

The systems are digital filters run by ``scipy.signal.lfilter`` (a route
independent of the library's own simulators); steady state is reached by
running two warm-up periods first (poles of radius 0.9: 0.9**512 ~ 1e-23).
Multisines are built here from their spectra so the amplitude at every line
is known exactly: ``|U_k| = |rfft(u)[k]|`` is the same for every line and
realisation, and the rms is 1.

Statistical tolerances are set from the number of independent chi-square
terms behind each estimate: a variance estimated with ``d`` complex degrees
of freedom has relative standard deviation ``1/sqrt(d)``, and averaging over
``K`` independent lines divides that by ``sqrt(K)``. Bounds are placed at
about four to five such standard deviations and all seeds are fixed, so the
tests are deterministic but would fail for any error of a constant factor
(a forgotten division by the number of periods or realisations is a factor
2 or more).
"""
import numpy as np
import pytest
import scipy.signal as ss

from sklearn_pnlss.frequency.bla import excited_lines, periodic_bla, welch_bla
from sklearn_pnlss.frequency.noise import periodic_noise_variance, signal_noise_variances

N = 256  # samples per period
# A resonator: poles 0.9 exp(+-0.6j), near bin 0.6 / (2 pi) * 256 = 24.4.
POLES = 0.9 * np.exp([0.6j, -0.6j])
A_FILT = np.real(np.poly(POLES))
B_FILT = np.array([0.2, 0.1, -0.05])


def frf_true(lines, b=B_FILT, a=A_FILT):
    return ss.freqz(b, a, worN=2 * np.pi * np.asarray(lines) / N)[1]


def amplitude(lines):
    """|rfft(u)_k| at every excited line of a unit-rms multisine: by
    Parseval, rms^2 = 2 K |U_k|^2 / N^2 for K lines (no DC or Nyquist)."""
    return N / np.sqrt(2 * len(lines))


def multisine(lines, n_real, n_per, rng, n_inputs=1):
    """Random-phase multisine of unit rms with the same amplitude
    ``amplitude(lines)`` at every line of the rfft, ``n_per`` periods each."""
    X = np.empty((n_real, n_per * N, n_inputs))
    for r in range(n_real):
        for i in range(n_inputs):
            spec = np.zeros(N // 2 + 1, dtype=complex)
            spec[lines] = amplitude(lines) * np.exp(2j * np.pi * rng.random(len(lines)))
            X[r, :, i] = np.tile(np.fft.irfft(spec, N), n_per)
    return X


def steady_state(x, b=B_FILT, a=A_FILT, warm=2):
    """Steady-state response of the filter to the periodic ``x`` (1-D)."""
    n_per = x.shape[0] // N
    return ss.lfilter(b, a, np.tile(x[:N], n_per + warm))[warm * N:]


def split(Z):
    """(R, P*N, c) -> list of (P, N, c), the layout periodic_bla expects."""
    return [z.reshape(-1, N, z.shape[-1]) for z in Z]


def linear_output(X):
    return np.stack([steady_state(x[:, 0]) for x in X])[:, :, None]


# --------------------------------------------------------------------------
# FRF of linear systems
# --------------------------------------------------------------------------

def test_frf_of_linear_filter_is_exact():
    """Noise-free steady state: Y_k = H(e^{j w_k}) U_k exactly, so the BLA is
    H at every excited line (to rounding), the lines are found from the
    input, and both variances vanish."""
    rng = np.random.default_rng(0)
    lines = np.arange(1, 101)
    X = multisine(lines, 3, 2, rng)
    res = periodic_bla(split(X), split(linear_output(X)))
    np.testing.assert_array_equal(res.lines, lines)
    assert res.frf.shape == (100, 1, 1)
    np.testing.assert_allclose(res.frf[:, 0, 0], frf_true(lines), rtol=1e-10, atol=0)
    H_scale = np.max(np.abs(frf_true(lines))) ** 2
    assert np.max(res.var_noise) < 1e-25 * H_scale
    assert np.max(res.var_total) < 1e-25 * H_scale
    assert (res.n_realizations, res.n_periods) == (3, 2)


def test_frf_two_inputs_two_outputs_is_exact():
    """With m = 2 inputs, each pair of realisations is one block and
    G = Y U^-1 per line; every one of the four entries is recovered."""
    rng = np.random.default_rng(1)
    lines = np.arange(2, 90, 3)
    filters = {  # (output, input) -> (b, a)
        (0, 0): (B_FILT, A_FILT),
        (0, 1): ([0.5, -0.2], [1.0, -0.5]),
        (1, 0): ([0.0, 1.0], [1.0, 0.3]),
        (1, 1): ss.butter(2, 0.4),
    }
    X = multisine(lines, 4, 2, rng, n_inputs=2)
    Y = np.zeros((4, 2 * N, 2))
    for (o, i), (b, a) in filters.items():
        for r in range(4):
            Y[r, :, o] += steady_state(X[r, :, i], b, a)
    res = periodic_bla(split(X), split(Y))
    assert res.frf.shape == (lines.size, 2, 2)
    for (o, i), (b, a) in filters.items():
        np.testing.assert_allclose(res.frf[:, o, i], frf_true(lines, b, a), rtol=1e-9, atol=1e-12)


def test_lines_argument_restricts_the_analysis():
    rng = np.random.default_rng(2)
    lines = np.arange(1, 51)
    X = multisine(lines, 2, 2, rng)
    sub = lines[::7]
    res = periodic_bla(split(X), split(linear_output(X)), lines=sub)
    np.testing.assert_array_equal(res.lines, sub)
    np.testing.assert_allclose(res.frf[:, 0, 0], frf_true(sub), rtol=1e-10)
    # line_kind: 0 at DC, 1 at the analysed lines, 2/3 at other odd/even bins.
    kind = res.line_kind
    assert kind.shape == (N // 2 + 1,) and kind[0] == 0
    np.testing.assert_array_equal(np.flatnonzero(kind == 1), sub)
    other = np.setdiff1d(np.arange(1, N // 2 + 1), sub)
    np.testing.assert_array_equal(kind[other], np.where(other % 2, 2, 3))


def test_excited_lines_threshold():
    """A line 40 dB below the others counts at -60 dB, not at -30 dB; DC
    never counts."""
    spec = np.zeros((1, N // 2 + 1, 1), dtype=complex)
    spec[0, [0, 3, 5, 9], 0] = [100.0, 1.0, 1.0, 1.0]
    spec[0, 7, 0] = 0.01  # power 1e-4 = -40 dB
    np.testing.assert_array_equal(excited_lines(spec), [3, 5, 7, 9])
    np.testing.assert_array_equal(excited_lines(spec, threshold_db=-30.0), [3, 5, 9])


# --------------------------------------------------------------------------
# Noise and nonlinear distortion levels
# --------------------------------------------------------------------------

R_NOISE, P_NOISE, SIGMA = 6, 4, 0.05
LINES_NOISE = np.arange(1, 101)


@pytest.fixture(scope="module")
def noisy_linear():
    """The resonator in steady state plus white output noise of std SIGMA."""
    rng = np.random.default_rng(3)
    X = multisine(LINES_NOISE, R_NOISE, P_NOISE, rng)
    Y = linear_output(X) + SIGMA * rng.standard_normal((R_NOISE, P_NOISE * N, 1))
    return X, Y


def test_noise_variance_of_frf_matches_injected_noise(noisy_linear):
    """White noise of std s has E|rfft(e)_k|^2 = N s^2 at every bin. The
    BLA averages P periods and R realisations and divides by |U_k|, so
    var(G_k) = N s^2 / (P R |U_k|^2).

    Tolerance: each line's estimate pools R (P - 1) = 18 complex degrees of
    freedom, relative std 1/sqrt(18); over K = 100 independent lines the
    mean has relative std 1/sqrt(1800) = 0.024; bound 0.12 (5 sigma)."""
    X, Y = noisy_linear
    res = periodic_bla(split(X), split(Y))
    expected = N * SIGMA**2 / (P_NOISE * R_NOISE * amplitude(LINES_NOISE) ** 2)
    assert np.mean(res.var_noise[:, 0, 0]) / expected == pytest.approx(1.0, abs=0.12)
    # Output noise level per bin (all bins 0..N/2, DC and Nyquist included:
    # the real DFT there has the same variance N s^2): of one period's
    # average, N s^2 / P. Pooled over 129 bins x 6 x 3 dof: bound 0.1.
    assert np.mean(res.noise_level[:, 0]) / (N * SIGMA**2 / P_NOISE) == pytest.approx(1.0, abs=0.1)
    # The estimate itself scatters around H with exactly that variance:
    # |G - H|^2 / var is a unit exponential per line, so its mean over 100
    # lines has std 0.1 -> bound 0.4 (4 sigma).
    z2 = np.abs(res.frf[:, 0, 0] - frf_true(LINES_NOISE)) ** 2 / expected
    assert np.mean(z2) == pytest.approx(1.0, abs=0.4)


def test_linear_system_has_no_nonlinear_distortion(noisy_linear):
    """For a linear system the spread over realisations is noise only:
    var_total estimates the same N s^2 / (P R |U_k|^2) as var_noise.

    Tolerance: var_total has R - 1 = 5 complex dof per line; over 100 lines
    the mean has relative std 1/sqrt(500) = 0.045; bound 0.22 (5 sigma).
    var_nonlinear = max(var_total - var_noise, 0) is then only the positive
    part of a zero-mean scatter, well below the noise level."""
    X, Y = noisy_linear
    res = periodic_bla(split(X), split(Y))
    expected = N * SIGMA**2 / (P_NOISE * R_NOISE * amplitude(LINES_NOISE) ** 2)
    assert np.mean(res.var_total[:, 0, 0]) / expected == pytest.approx(1.0, abs=0.22)
    assert np.mean(res.var_nonlinear) < 0.5 * np.mean(res.var_noise)
    np.testing.assert_array_equal(res.var_nonlinear, np.maximum(res.var_total - res.var_noise, 0.0))


@pytest.fixture(scope="module")
def wiener_cubic():
    """The resonator followed by y = v + a v^3, R = 40 realisations."""
    rng = np.random.default_rng(4)
    lines = np.arange(1, 61)
    X = multisine(lines, 40, 2, rng)
    V = linear_output(X)
    a, sigma = 0.1, 0.01
    Y = V + a * V**3 + sigma * rng.standard_normal(V.shape)
    return X, V, Y, lines, a


def test_cubic_distortion_dominates_noise(wiener_cubic):
    X, V, Y, lines, a = wiener_cubic
    res = periodic_bla(split(X), split(Y))
    # Measured ~3000; a linear system gives ~0 (previous test).
    assert np.median(res.var_nonlinear / res.var_noise) > 100


def test_cubic_bla_matches_bussgang_gain(wiener_cubic):
    """BLA of a Wiener system v -> v + a v^3 under a random-phase multisine.

    Writing v = sum_l V_l e^{j w_l t} (l = +-1..+-F, V_-l = conj(V_l)), the
    part of v^3 at line k that is coherent with U_k (independent uniform
    phases) is the sum over the index triples {k, l, -l}:
    V_k (6 sum_{l>0} |V_l|^2 - 3 |V_k|^2) = 3 V_k (sigma_v^2 - |V_k|^2), so

        G_BLA(k) = H_k (1 + 3 a (sigma_v^2 - |V_k|^2)),

    Bussgang's 1 + 3 a sigma^2 for a Gaussian input, minus a finite-line
    term. What remains in one estimate is the stochastic distortion, whose
    variance var_total estimates: the mean of |G - G_BLA|^2 / var_total over
    60 lines must be near 1 (measured 0.8-1.3 over 12 seeds, and ~8 for the
    wrong gain 1 + 2 a sigma^2, ~60 for the linear part H alone)."""
    X, V, Y, lines, a = wiener_cubic
    res = periodic_bla(split(X), split(Y))
    Vk = np.fft.rfft(V[0, :N, 0])[lines] / N  # same |V_k| in every realisation
    sigma2 = 2 * np.sum(np.abs(Vk) ** 2)
    assert sigma2 == pytest.approx(np.mean(V**2), rel=1e-12)  # Parseval
    G_bla = frf_true(lines) * (1 + 3 * a * (sigma2 - np.abs(Vk) ** 2))
    z2 = np.abs(res.frf[:, 0, 0] - G_bla) ** 2 / res.var_total[:, 0, 0]
    assert 0.5 < np.mean(z2) < 2.0
    z2_linear_part = np.abs(res.frf[:, 0, 0] - frf_true(lines)) ** 2 / res.var_total[:, 0, 0]
    assert np.mean(z2_linear_part) > 20


def random_odd_lines(f_max, rng):
    """Odd bins up to f_max with one random bin of every three left out
    (the detection lines for odd distortion)."""
    odd = np.arange(1, f_max + 1, 2)
    groups = odd[: odd.size // 3 * 3].reshape(-1, 3)
    keep = np.ones(groups.shape, bool)
    keep[np.arange(groups.shape[0]), rng.integers(0, 3, groups.shape[0])] = False
    return np.concatenate([groups[keep], odd[odd.size // 3 * 3:]])


@pytest.mark.parametrize("kind", ["even", "odd"])
def test_odd_and_even_detection_lines(kind):
    """Random-odd multisine (odd lines excited, one odd line in three left
    out) into a Wiener system v -> v + c v^2 or v + c v^3.

    Even-order terms combine two odd lines into even ones (and DC); odd-order
    terms combine three odd lines into odd ones only. So the even detection
    lines (line_kind 3) carry power for x^2 and only noise for x^3, and the
    non-excited odd lines (line_kind 2) the other way round. Where a line
    carries only noise its output power (mean |Y_mean|^2 over R = 8
    realisations) equals noise_level, N s^2 / P. The smaller set is the 43
    non-excited odd lines (64 odd bins, 21 excited): the mean output power
    has relative std 1/sqrt(43 * 8) = 0.054, the noise level
    1/sqrt(43 * 8 * 3) = 0.031, so the ratio is 1 within 0.3 (~5 sigma)."""
    rng = np.random.default_rng(5)
    lines = random_odd_lines(61, rng)
    assert lines.size == 21
    X = multisine(lines, 8, 4, rng)
    V = linear_output(X)
    sigma = 1e-3
    nl = 0.2 * V**2 if kind == "even" else 0.2 * V**3
    Y = V + nl + sigma * rng.standard_normal(V.shape)
    res = periodic_bla(split(X), split(Y))
    np.testing.assert_array_equal(res.lines, lines)
    level, noise = res.output_level[:, 0], res.noise_level[:, 0]
    even_lines = res.line_kind == 3
    odd_lines = res.line_kind == 2
    assert np.mean(noise) / (N * sigma**2 / 4) == pytest.approx(1.0, abs=0.1)
    lit, dark = (even_lines, odd_lines) if kind == "even" else (odd_lines, even_lines)
    assert 10 * np.log10(np.mean(level[lit]) / np.mean(noise[lit])) > 30
    assert np.mean(level[dark]) / np.mean(noise[dark]) == pytest.approx(1.0, abs=0.3)


# --------------------------------------------------------------------------
# Degenerate designs and bad input
# --------------------------------------------------------------------------

def test_one_period_leaves_noise_unknown():
    rng = np.random.default_rng(6)
    lines = np.arange(1, 41)
    X = multisine(lines, 3, 1, rng)
    res = periodic_bla(split(X), split(linear_output(X)))
    np.testing.assert_allclose(res.frf[:, 0, 0], frf_true(lines), rtol=1e-10)
    assert np.all(np.isnan(res.var_noise)) and np.all(np.isnan(res.var_nonlinear))
    assert np.all(np.isnan(res.noise_level))
    assert np.all(np.isfinite(res.var_total))


def test_one_realisation_total_equals_noise(noisy_linear):
    X, Y = noisy_linear
    res = periodic_bla(split(X[:1]), split(Y[:1]))
    np.testing.assert_array_equal(res.var_total, res.var_noise)
    np.testing.assert_array_equal(res.var_nonlinear, 0.0)


def test_zero_input_is_rejected():
    with pytest.raises(ValueError, match="No excited line"):
        periodic_bla([np.zeros((2, N, 1))], [np.ones((2, N, 1))])


def test_realisations_not_a_multiple_of_inputs_rejected():
    rng = np.random.default_rng(7)
    X = multisine(np.arange(1, 20), 3, 1, rng, n_inputs=2)
    with pytest.raises(ValueError, match="multiple of 2"):
        periodic_bla(split(X), split(X[:, :, :1]))


def test_dependent_experiments_rejected():
    """Two identical experiments cannot separate two inputs: U is singular."""
    rng = np.random.default_rng(8)
    X = multisine(np.arange(1, 20), 1, 1, rng, n_inputs=2)
    X = np.concatenate([X, X])
    with pytest.raises(ValueError, match="independent excitation"):
        periodic_bla(split(X), split(X[:, :, :1]))


# --------------------------------------------------------------------------
# periodic_noise_variance
# --------------------------------------------------------------------------

def test_periodic_noise_variance_of_white_noise():
    """Unitary DFT (rfft / sqrt(N)) of white noise of std s: variance s^2 at
    every bin. The periodic signal underneath is removed by the period mean.
    Signals that are not a whole number of periods, or only one, are left
    out. Pooled dof per bin 4 + 2 = 6; over 129 bins the mean has relative
    std about 1/sqrt(6 * 129) = 0.036; bound 0.15."""
    rng = np.random.default_rng(9)
    s = 0.2
    X = multisine(np.arange(1, 60), 1, 5, rng)[0, :, 0]
    clean = steady_state(X)
    y_list = [
        (clean + s * rng.standard_normal(clean.size))[:, None],  # 5 periods
        (clean[: 3 * N] + s * rng.standard_normal(3 * N))[:, None],  # 3 periods
        100 * rng.standard_normal((2 * N + 7, 1)),  # not periodic: ignored
        100 * rng.standard_normal((N, 1)),  # one period: ignored
    ]
    var = periodic_noise_variance(y_list, N)
    assert var.shape == (N // 2 + 1, 1)
    assert np.mean(var) / s**2 == pytest.approx(1.0, abs=0.15)
    assert periodic_noise_variance(y_list[2:], N) is None
    assert periodic_noise_variance(y_list, None) is None


def test_periodic_noise_variance_agrees_with_bla_noise_level(noisy_linear):
    """Same data, two routes: with equal P the pooled unitary variance times
    N / P is periodic_bla's noise_level (both average equal-dof estimates)."""
    X, Y = noisy_linear
    var = periodic_noise_variance(list(Y), N)
    res = periodic_bla(split(X), split(Y))
    np.testing.assert_allclose(var * N / P_NOISE, res.noise_level, rtol=1e-10)


def test_each_signal_keeps_its_own_noise():
    """Two levels of a campaign with noise std 0.01 and 0.1: each signal's
    estimate is its own (pooled, the quiet one would read 0.5 of the loud
    one's variance, 50 times its own). Smoothed to 64 real degrees of
    freedom: 5 periods (8 per bin) over 8 bins, so across 129 bins the
    mean is within a few percent and no bin is off by a factor 2 (64 dof:
    relative std 0.18). A signal of one period gets the pooled variance."""
    rng = np.random.default_rng(11)
    x = multisine(np.arange(1, 60), 1, 5, rng)[0, :, 0]
    clean = steady_state(x)
    quiet = (clean + 0.01 * rng.standard_normal(clean.size))[:, None]
    loud = (10 * clean + 0.1 * rng.standard_normal(clean.size))[:, None]
    single = loud[:N]
    own = signal_noise_variances([quiet, loud, single], N)
    for var, s in zip(own[:2], (0.01, 0.1)):
        assert var.shape == (N // 2 + 1, 1)
        assert np.mean(var) / s**2 == pytest.approx(1.0, abs=0.1)
        assert np.all((var > 0.5 * s**2) & (var < 2 * s**2))
    np.testing.assert_array_equal(own[2], periodic_noise_variance([quiet, loud, single], N))
    assert signal_noise_variances([single], N) is None


def test_trend_removal_keeps_drift_out_of_the_noise():
    """A structure whose response grows linearly with the period index
    (y_p = (1 + c p) y_ss) is not noise. With trend_degree=0 the residual at
    bin k is c (p - mean p) Y_k + noise, so the estimate is
    s^2 + c^2 var(p) |Y_k|^2 (var with ddof=1, Y_k unitary DFT of y_ss).
    With trend_degree=1 each bin's linear trend over periods is removed
    (P - 2 = 6 dof left) and the estimate is s^2 again."""
    rng = np.random.default_rng(10)
    s, P, c = 0.01, 8, 0.02
    lines = np.arange(1, 60)
    x = multisine(lines, 1, P, rng)[0, :, 0]
    y_ss = steady_state(x).reshape(P, N)
    drift = (1 + c * np.arange(P))[:, None]
    y = (drift * y_ss).ravel() + s * rng.standard_normal(P * N)
    var0 = periodic_noise_variance([y[:, None]], N)[:, 0]
    var1 = periodic_noise_variance([y[:, None]], N, trend_degree=1)[:, 0]
    # 6 dof x 129 bins: relative std 0.036; bound 0.15.
    assert np.mean(var1) / s**2 == pytest.approx(1.0, abs=0.15)
    Yk2 = np.abs(np.fft.rfft(y_ss[0])) ** 2 / N
    expected0 = s**2 + c**2 * np.var(np.arange(P), ddof=1) * Yk2
    assert np.mean(expected0[lines]) > 30 * s**2  # the drift matters here
    # The signal x noise cross term has zero mean; over 59 lines with 7 dof
    # each, 0.1 is several standard deviations.
    assert np.mean(var0[lines]) / np.mean(expected0[lines]) == pytest.approx(1.0, abs=0.1)
    # Degree capped at P - 2: with P = 2 a degree-5 request is degree 0.
    two = y[: 2 * N, None]
    np.testing.assert_array_equal(
        periodic_noise_variance([two], N, trend_degree=5), periodic_noise_variance([two], N)
    )


# --------------------------------------------------------------------------
# welch_bla (non-periodic data)
# --------------------------------------------------------------------------

def test_welch_bla_of_filtered_white_noise():
    """H1 estimate from white-noise input through a Butterworth filter (poles
    of radius 0.52, so leakage is small) with output noise.

    Noise-free, the error is leakage of the Hann-windowed segments only
    (measured 0.012-0.016 over six seeds, |H| <= 1): bound 0.03. With output
    noise, the returned variance predicts the actual error: mean
    |G - H|^2 / var over the 64 lines measured 0.9-1.4 over six seeds (50 %
    overlap correlates neighbouring segments, so ~1.2 rather than 1); bound
    0.5-2, far from a factor n_seg = 311 error either way."""
    rng = np.random.default_rng(11)
    b, a = ss.butter(2, 0.3)
    nper = 128
    U = [rng.standard_normal((20000, 1)) for _ in range(2)]
    Y0 = [ss.lfilter(b, a, u[:, 0])[:, None] for u in U]
    lines, frf, var = welch_bla(U, Y0, nper)
    np.testing.assert_array_equal(lines, np.arange(1, nper // 2 + 1))
    H = ss.freqz(b, a, worN=2 * np.pi * lines / nper)[1]
    assert np.max(np.abs(frf[:, 0, 0] - H)) < 0.03
    Y = [y + 0.3 * rng.standard_normal(y.shape) for y in Y0]
    lines, frf, var = welch_bla(U, Y, nper)
    z2 = np.abs(frf[:, 0, 0] - H) ** 2 / var[:, 0, 0]
    assert 0.5 < np.mean(z2) < 2.0
