"""Training signals turned into simulation segments (``statespace/segments.py``):
the transient length against hand computations, period averaging against the
noise reduction it promises, the layout of the segments, and the claim the
module rests on: a model simulated from rest on a segment (prepended
transient included) reproduces the periodic steady state once the transient
is skipped.
"""
import numpy as np
import pytest

from sklearn_pnlss.statespace.linear import periodic_initial_state, simulate_linear, simulate_linear_signal
from sklearn_pnlss.statespace.segments import average_periods, make_segments, transient_length

PERIOD = 512


def rotation(radius, angle):
    c, s = np.cos(angle), np.sin(angle)
    return radius * np.array([[c, -s], [s, c]])


# --------------------------------------------------------------------------
# transient_length
# --------------------------------------------------------------------------

@pytest.mark.parametrize(
    "A, period, tol, expected",
    [
        # ln(1e-9) / ln(0.9) = -20.7233 / -0.105361 = 196.69 -> 197
        (np.diag([0.9, 0.5]), 1000, 1e-9, 197),
        # slowest mode decides: a pair of radius 0.95, 404.015 -> 405
        (np.block([[rotation(0.95, 0.7), np.zeros((2, 1))], [np.zeros((1, 2)), 0.3]]), 1000, 1e-9, 405),
        # at most one period
        (np.diag([0.9]), 100, 1e-9, 100),
        # at least 10: ln(1e-9) / ln(0.1) = 9
        (np.diag([0.1, -0.05]), 1000, 1e-9, 10),
        # tol used: ln(1e-6) / ln(0.5) = 19.93 -> 20; a negative pole counts by its modulus
        (np.diag([-0.5, 0.2]), 1000, 1e-6, 20),
        # unstable or marginally stable: a whole period
        (np.diag([1.0, 0.5]), 300, 1e-9, 300),
        (rotation(1.1, 0.2), 300, 1e-9, 300),
    ],
)
def test_transient_length_hand_computed(A, period, tol, expected):
    assert transient_length(A, period, tol=tol) == expected


@pytest.mark.parametrize("rho", [0.3, 0.7, 0.9, 0.97, 0.995])
def test_transient_length_is_the_first_decay_below_tol(rho):
    """Unclipped, n is the smallest integer with rho**n <= tol."""
    n = transient_length(np.diag([rho, rho / 2]), 10**6)
    assert n > 10  # not clipped: 0.3**10 = 6e-6 is still above tol
    assert rho**n <= 1e-9 < rho ** (n - 1)


def test_transient_length_of_nilpotent_matrix():
    """A nilpotent A (spectral radius 0, an FIR model) forgets its state
    after n = 3 samples, so anything from the minimum 10 up to the period is
    correct. (The formula has no log(0) and currently returns the whole
    period: conservative, not wrong.) No error or warning either."""
    A = np.diag([1.0, 1.0], k=1)  # 3x3 shift, A**3 = 0
    assert 10 <= transient_length(A, 200) <= 200


# --------------------------------------------------------------------------
# average_periods
# --------------------------------------------------------------------------

def test_averaging_divides_noise_variance_by_periods():
    """y = periodic part + white noise of std s; the mean of P periods has
    noise variance s^2 / P. Estimated over 2048 samples (relative std of a
    variance estimate sqrt(2 / 2048) = 0.031): bound 0.15 (5 sigma)."""
    rng = np.random.default_rng(0)
    period, P, s = 2048, 8, 0.5
    u = rng.standard_normal((period, 1))
    clean = np.sin(2 * np.pi * 3 * np.arange(period) / period)[:, None]
    U = np.tile(u, (P, 1))
    Y = np.tile(clean, (P, 1)) + s * rng.standard_normal((P * period, 1))
    U_avg, Y_avg, W = average_periods(U, Y, period)
    assert W is None
    np.testing.assert_allclose(U_avg, u, rtol=1e-14)
    assert np.var(Y_avg - clean) / (s**2 / P) == pytest.approx(1.0, abs=0.15)


def test_weighted_average_keeps_the_least_squares_optimum():
    """sum_p w_p (yhat - y_p)^2 = (sum_p w_p) (yhat - ybar_w)^2 + const,
    checked on two arbitrary predictions: the difference of the costs is
    the same computed either way."""
    rng = np.random.default_rng(1)
    period, P = 50, 4
    U = np.tile(rng.standard_normal((period, 1)), (P, 1))
    Y = rng.standard_normal((P * period, 2))
    W = rng.random((P * period, 2))
    W[:period, 0] = 0.0  # a period left out of output 0 entirely
    U_avg, Y_avg, W_sum = average_periods(U, Y, period, W)
    np.testing.assert_allclose(W_sum, W.reshape(P, period, 2).sum(axis=0))
    # Output 0 ignores the first period: its average is that of periods 2..4.
    Wp, Yp = W.reshape(P, period, 2), Y.reshape(P, period, 2)
    np.testing.assert_allclose(
        Y_avg[:, 0], (Wp[1:, :, 0] * Yp[1:, :, 0]).sum(0) / Wp[1:, :, 0].sum(0), rtol=1e-12
    )

    def full_cost(yhat):
        return np.sum(Wp * (yhat[None] - Yp) ** 2)

    def averaged_cost(yhat):
        return np.sum(W_sum * (yhat - Y_avg) ** 2)

    y1, y2 = rng.standard_normal((2, period, 2))
    assert full_cost(y1) - full_cost(y2) == pytest.approx(averaged_cost(y1) - averaged_cost(y2), rel=1e-10)


def test_zero_total_weight_gives_zero_target():
    """Samples weighted zero in every period carry no information: target 0
    and weight 0 (no division by zero)."""
    period, P = 10, 3
    Y = np.ones((P * period, 1))
    W = np.ones_like(Y)
    W[3::period] = 0.0
    _, Y_avg, W_sum = average_periods(np.zeros_like(Y), Y, period, W)
    assert W_sum[3, 0] == 0.0 and Y_avg[3, 0] == 0.0
    np.testing.assert_array_equal(np.delete(Y_avg, 3), 1.0)
    np.testing.assert_array_equal(np.delete(W_sum, 3), 3.0)


# --------------------------------------------------------------------------
# make_segments: layout
# --------------------------------------------------------------------------

def test_periodic_segment_layout():
    """A periodic signal keeps all its samples as target; the last n_tr
    input samples are prepended, and n_skip = n_tr."""
    rng = np.random.default_rng(2)
    period, P = 40, 3
    U = np.tile(rng.standard_normal((period, 1)), (P, 1))
    Y = rng.standard_normal((P * period, 2))
    (seg,) = make_segments([U], [Y], period=period, n_transient=15)
    assert seg.n_skip == 15 and seg.period == period
    np.testing.assert_array_equal(seg.U, np.vstack([U[-15:], U]))
    np.testing.assert_array_equal(seg.Y, Y)
    assert seg.time_weight is None and seg.freq_weight is None
    # The prepended samples are one period's tail: equal to the samples
    # just before the data start in a periodic continuation.
    np.testing.assert_array_equal(seg.U[:15], U[period - 15:period])


def test_averaged_segment_layout_and_freq_weight():
    rng = np.random.default_rng(3)
    period, P = 40, 5
    U = np.tile(rng.standard_normal((period, 1)), (P, 1))
    Y = rng.standard_normal((P * period, 1))
    calls = []

    def freq_weight(i, n_averaged):
        calls.append(n_averaged)
        return np.full((period // 2 + 1, 1), float(n_averaged))

    (seg,) = make_segments([U], [Y], period=period, n_transient=100, average=True, freq_weight=freq_weight)
    # Averaged to one period; the transient is capped at that period.
    assert seg.n_skip == period and seg.Y.shape == (period, 1)
    np.testing.assert_allclose(seg.Y, Y.reshape(P, period, 1).mean(0))
    np.testing.assert_allclose(seg.U, np.vstack([U[:period], U[:period]]))
    assert calls == [P] and np.all(seg.freq_weight == P)
    # Without averaging each target period is one measured period.
    (seg,) = make_segments([U], [Y], period=period, n_transient=10, freq_weight=freq_weight)
    assert calls[-1] == 1 and seg.Y.shape == (P * period, 1)
    # A single period is not "averaged" (n_averaged stays 1).
    make_segments([U[:period]], [Y[:period]], period=period, n_transient=10, average=True,
                  freq_weight=freq_weight)
    assert calls[-1] == 1


def test_averaged_segment_time_weights():
    """Per-sample weights of one output column broadcast to Y's shape; after
    averaging, the weight is their sum over periods."""
    period, P = 20, 4
    U = np.zeros((P * period, 1))
    Y = np.arange(P * period, dtype=float)[:, None] * np.ones((1, 2))
    w = np.linspace(1, 2, P * period)[:, None]
    (seg,) = make_segments([U], [Y], period=period, n_transient=5, average=True, time_weights=[w])
    W = np.broadcast_to(w, Y.shape).reshape(P, period, 2)
    np.testing.assert_allclose(seg.time_weight, W.sum(0))
    np.testing.assert_allclose(seg.Y, (W * Y.reshape(P, period, 2)).sum(0) / W.sum(0))


def test_non_periodic_segments_skip_samples():
    rng = np.random.default_rng(4)
    U1, Y1 = rng.standard_normal((100, 1)), rng.standard_normal((100, 1))
    U2, Y2 = rng.standard_normal((7, 1)), rng.standard_normal((7, 1))
    w1 = rng.random((100, 1))
    s1, s2 = make_segments([U1, U2], [Y1, Y2], period=30, n_transient=12, n_skip=9,
                           time_weights=[w1, np.ones((7, 1))])
    # 100 and 7 are not multiples of 30: simulated from rest, first 9 out.
    assert s1.n_skip == 9 and s1.period is None
    np.testing.assert_array_equal(s1.U, U1)
    np.testing.assert_array_equal(s1.Y, Y1[9:])
    np.testing.assert_array_equal(s1.time_weight, w1[9:])
    # A signal shorter than n_skip keeps its last sample.
    assert s2.n_skip == 6 and s2.Y.shape == (1, 1)
    np.testing.assert_array_equal(s2.Y, Y2[6:])
    # period=None: every signal is from rest, even a "whole number of periods".
    (s3,) = make_segments([U1], [Y1], period=None, n_transient=12, n_skip=3)
    assert s3.n_skip == 3 and s3.U.shape == (100, 1)


def test_mixed_signals_each_get_their_rule():
    rng = np.random.default_rng(5)
    period = 25
    U = [rng.standard_normal((n, 1)) for n in (50, 60, 25)]
    Y = [rng.standard_normal((n, 1)) for n in (50, 60, 25)]
    segs = make_segments(U, Y, period=period, n_transient=40, n_skip=4)
    # 50: two periods, transient capped at the signal length (50 >= 40);
    # 60: from rest; 25: one period, transient capped at 25.
    assert [s.n_skip for s in segs] == [40, 4, 25]
    assert [s.U.shape[0] for s in segs] == [90, 60, 50]
    assert [s.Y.shape[0] for s in segs] == [50, 56, 25]


# --------------------------------------------------------------------------
# A model simulated on a segment reproduces the steady state
# --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def linear_system():
    """Four states: slowest pole 0.9 (real), a pair of radius 0.6, one at
    -0.4; a random basis so nothing is diagonal."""
    rng = np.random.default_rng(6)
    A0 = np.zeros((4, 4))
    A0[0, 0], A0[1:3, 1:3], A0[3, 3] = 0.9, rotation(0.6, 1.0), -0.4
    T = rng.standard_normal((4, 4))
    A = T @ A0 @ np.linalg.inv(T)
    B = T @ rng.standard_normal((4, 1))
    C = rng.standard_normal((1, 4)) @ np.linalg.inv(T)
    D = np.array([[0.2]])
    return A, B, C, D


def simulate_segment(model, seg):
    """Simulate from rest on the whole segment input, compare after n_skip."""
    y = simulate_linear(*model, seg.U)[0]
    return y[seg.n_skip:]


def test_segment_simulation_reproduces_steady_state(linear_system):
    """Steady state from the exact periodic initial state; the segment is
    simulated from rest with transient_length(A) = 197 samples prepended
    (0.9**197 = 1e-9): the output matches to ~1e-9 of its size."""
    A, B, C, D = linear_system
    rng = np.random.default_rng(7)
    P = 3
    U = np.tile(rng.standard_normal((PERIOD, 1)), (P, 1))
    Y = simulate_linear_signal(A, B, C, D, U, periodic_with=PERIOD)
    n_tr = transient_length(A, PERIOD)
    assert n_tr == 197
    (seg,) = make_segments([U], [Y], period=PERIOD, n_transient=n_tr)
    err = np.max(np.abs(simulate_segment(linear_system, seg) - Y))
    scale = np.max(np.abs(Y))
    assert err < 1e-8 * scale
    # Without the prepended transient the first samples are far off: the
    # error starts at the size of the steady-state response itself.
    (bare,) = make_segments([U], [Y], period=PERIOD, n_transient=0)
    assert np.max(np.abs(simulate_segment(linear_system, bare) - Y)) > 1e-2 * scale
    # A shorter transient of n samples starts the data from A^n x(N - n)
    # short of the steady state x(0) = x(N) (x(N - n): the steady state
    # n samples before the period ends), so the error is exactly the free
    # response from -A^n x(N - n); it decays like the slowest pole.
    n = 60
    (short,) = make_segments([U], [Y], period=PERIOD, n_transient=n)
    err = simulate_segment(linear_system, short) - Y
    x0 = periodic_initial_state(A, B, C, D, U[:PERIOD])
    x_before = simulate_linear(A, B, C, D, U[: PERIOD - n], x0)[1]
    missing = -np.linalg.matrix_power(A, n) @ x_before
    zeros = np.zeros_like(D)
    free = simulate_linear(A, np.zeros_like(B), C, zeros, np.zeros_like(U), missing)[0]
    assert np.max(np.abs(err)) > 1e-5 * scale  # not negligible at n = 60
    np.testing.assert_allclose(err, free, rtol=0, atol=1e-12 * scale)


def test_averaged_segment_residual_is_noise_over_periods(linear_system):
    """Noisy steady-state data (white noise of std s), periods averaged: the
    true model's residual on the segment is the averaged noise, rms
    s / sqrt(P). Over 512 samples the rms has relative std
    1 / sqrt(2 * 512) = 0.03: bound 0.15."""
    A, B, C, D = linear_system
    rng = np.random.default_rng(8)
    P, s = 8, 0.05
    U = np.tile(rng.standard_normal((PERIOD, 1)), (P, 1))
    Y = simulate_linear_signal(A, B, C, D, U, periodic_with=PERIOD) + s * rng.standard_normal((P * PERIOD, 1))
    (seg,) = make_segments([U], [Y], period=PERIOD, n_transient=transient_length(A, PERIOD), average=True)
    residual = simulate_segment(linear_system, seg) - seg.Y
    assert np.sqrt(np.mean(residual**2)) / (s / np.sqrt(P)) == pytest.approx(1.0, abs=0.15)
    # Not averaged: the residual is the raw noise, rms s.
    (raw,) = make_segments([U], [Y], period=PERIOD, n_transient=transient_length(A, PERIOD))
    residual = simulate_segment(linear_system, raw) - raw.Y
    assert np.sqrt(np.mean(residual**2)) / s == pytest.approx(1.0, abs=0.05)


def test_a_long_record_cut_for_threads_loses_nothing():
    """A record that does not start from rest, cut into pieces that each
    start from the state their own first samples show: the pieces cover it
    without overlap, and the linear model that made it reproduces every
    piece to round-off (the cut is exact where the window pins the state)."""
    from sklearn_pnlss.statespace.scaled import linear_scaled_model

    A, B, C, D = rotation(0.9, 0.3), np.array([[1.0], [0.5]]), np.array([[1.0, -0.4]]), np.zeros((1, 1))
    U = np.random.default_rng(3).standard_normal((4000, 1))
    Y = simulate_linear(A, B, C, D, U, np.array([2.0, -1.0]))[0]  # not from rest
    segs = make_segments([U], [Y], period=None, n_transient=0, init_window=40, pieces=3)
    assert [s.U.shape[0] for s in segs] == [1333, 1333, 1334]
    np.testing.assert_array_equal(np.concatenate([s.Y for s in segs]), Y)
    model = linear_scaled_model(A, B, C, D).normalised
    for seg in segs:
        assert seg.init_window == 40
        assert np.max(np.abs(model.segment_error(seg))) < 1e-9
    # Pieces never get shorter than four windows.
    assert len(make_segments([U], [Y], period=None, n_transient=0, init_window=400, pieces=8)) == 2
