"""Frequency-domain subspace identification (``statespace/subspace.py``) on
systems whose poles are known.

Exact FRF data must give the poles to rounding; noisy data must give poles
whose error is first order in the noise, and a weighted residual that has
the size of a chi-square of the noise (the estimate fits the data as well as
the truth does, not better and not much worse).
"""
import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from sklearn_pnlss.statespace.linear import frequency_response, is_stable
from sklearn_pnlss.statespace.subspace import fd_refine, fd_subspace, frf_weights

N_DFT = 256
K_LINES = np.arange(1, 100)
Z = np.exp(2j * np.pi * K_LINES / N_DFT)


def rotation(radius, angle):
    c, s = np.cos(angle), np.sin(angle)
    return radius * np.array([[c, -s], [s, c]])


def make_system(m=1, p=1, seed=0, pairs=((0.95, 0.3), (0.8, 1.2))):
    """Block-diagonal complex pole pairs ``r exp(+-j angle)``, hidden by a
    random change of state basis so the identification cannot lean on the
    structure."""
    rng = np.random.default_rng(seed)
    n = 2 * len(pairs)
    A = np.zeros((n, n))
    for i, (r, th) in enumerate(pairs):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = rotation(r, th)
    poles = np.concatenate([[r * np.exp(1j * th), r * np.exp(-1j * th)] for r, th in pairs])
    T = rng.standard_normal((n, n))
    A = T @ A @ np.linalg.inv(T)
    B = T @ rng.standard_normal((n, m))
    C = rng.standard_normal((p, n)) @ np.linalg.inv(T)
    D = rng.standard_normal((p, m))
    return (A, B, C, D), poles


def pole_error(A, poles):
    """Largest distance between the eigenvalues of A and the true poles,
    after pairing them optimally (sorting would mis-pair near-equal poles)."""
    est = np.linalg.eigvals(A)
    dist = np.abs(est[:, None] - poles[None, :])
    rows, cols = linear_sum_assignment(dist)
    return dist[rows, cols].max()


def weighted_cost(model, G, var):
    return np.sum(np.abs(frequency_response(*model, Z) - G) ** 2 / var)


def add_noise(G, sd, seed):
    """Circular complex Gaussian noise with E|e|^2 = sd^2."""
    rng = np.random.default_rng(seed)
    return G + sd * (rng.standard_normal(G.shape) + 1j * rng.standard_normal(G.shape)) / np.sqrt(2)


# --------------------------------------------------------------------------
# Exact data
# --------------------------------------------------------------------------

def test_exact_frf_gives_exact_poles_siso():
    model, poles = make_system()
    G = frequency_response(*model, Z)
    A, B, C, D = fd_subspace(G, Z, 4)
    assert pole_error(A, poles) < 1e-10  # measured ~1e-15
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, rtol=0, atol=1e-10)
    np.testing.assert_allclose(D, model[3], atol=1e-10)


def test_exact_frf_gives_exact_poles_mimo():
    """Two inputs, two outputs, four states: all four FRF entries share the
    poles, and the model reproduces each of them."""
    model, poles = make_system(m=2, p=2, seed=1)
    G = frequency_response(*model, Z)
    A, B, C, D = fd_subspace(G, Z, 4)
    assert (B.shape, C.shape, D.shape) == ((4, 2), (2, 4), (2, 2))
    assert pole_error(A, poles) < 1e-10
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, rtol=0, atol=1e-10)


def test_weighted_exact_frf_still_exact():
    """Weights change how noise is balanced, not the solution of consistent
    data: variances spread over six decades give the same exact poles."""
    model, poles = make_system(seed=2)
    G = frequency_response(*model, Z)
    var = np.geomspace(1e-8, 1e-2, K_LINES.size)[:, None, None] * np.ones(G.shape)
    A, B, C, D = fd_subspace(G, Z, 4, var=var)
    assert pole_error(A, poles) < 1e-8
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, rtol=0, atol=1e-9)


def test_without_feedthrough():
    (A0, B0, C0, _), poles = make_system(seed=3)
    D0 = np.zeros((1, 1))
    G = frequency_response(A0, B0, C0, D0, Z)
    A, B, C, D = fd_subspace(G, Z, 4, estimate_d=False)
    np.testing.assert_array_equal(D, 0.0)
    assert pole_error(A, poles) < 1e-10
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, atol=1e-10)


def test_real_poles_and_odd_order():
    """Three states, real poles 0.5, -0.3 and 0.9: also recovered exactly,
    with a non-default number of block rows q."""
    rng = np.random.default_rng(4)
    poles = np.array([0.5, -0.3, 0.9])
    T = rng.standard_normal((3, 3))
    A0 = T @ np.diag(poles) @ np.linalg.inv(T)
    model = (A0, rng.standard_normal((3, 1)), rng.standard_normal((1, 3)), np.zeros((1, 1)))
    G = frequency_response(*model, Z)
    A, B, C, D = fd_subspace(G, Z, 3, q=10)
    assert pole_error(A, poles.astype(complex)) < 1e-10
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, atol=1e-10)


def test_unstable_pole_is_reflected():
    """A pole pair of radius 1.25 is identified, then reflected to
    1 / conj(lambda) (radius 0.8, same angle); the stable pair is kept."""
    model, poles = make_system(seed=5, pairs=((1.25, 0.5), (0.7, 1.5)))
    G = frequency_response(*model, Z)
    A, *_ = fd_subspace(G, Z, 4)
    assert is_stable(A)
    reflected = np.where(np.abs(poles) > 1, 1 / np.conj(poles), poles)
    assert pole_error(A, reflected) < 1e-8


# --------------------------------------------------------------------------
# Noisy data
# --------------------------------------------------------------------------

def test_pole_error_is_first_order_in_the_noise():
    """The estimator is a smooth function of the data that is exact at zero
    noise, so the same noise pattern scaled by 10 must scale the pole error
    by 10 (to within the second-order term: measured 10.00 +- 0.01)."""
    model, poles = make_system()
    G = frequency_response(*model, Z)
    noise = add_noise(np.zeros_like(G), 1.0, seed=0)
    e1 = pole_error(fd_subspace(G + 1e-6 * noise, Z, 4)[0], poles)
    e2 = pole_error(fd_subspace(G + 1e-5 * noise, Z, 4)[0], poles)
    assert e1 > 1e-9  # the noise does move the poles
    assert e2 / e1 == pytest.approx(10.0, rel=0.02)


def test_noisy_frf_poles_and_chi_square_fit():
    """|G| lies in 0.12-2.9; complex noise of std 0.01 per line, 8 seeds.

    Pole error: measured 3e-4 to 1.1e-3 (subspace), bound 3e-3.

    Fit: with a variance-weighted residual, the true model's cost is a sum
    of K = 99 unit exponentials; a maximum-likelihood fit absorbs half a
    unit per free real parameter (n (m + p) + m p = 9), so the refined cost
    has mean 99 - 4.5 = 94.5 and std ~sqrt(94.5) = 9.7 per seed; its mean
    over 8 seeds is within 14 of 94.5 (4 sigma). fd_refine never returns a
    worse fit than its start, and the subspace start is close to optimal
    (within 10 %)."""
    model, poles = make_system()
    G = frequency_response(*model, Z)
    sd = 0.01
    var = np.full(G.shape, sd**2)
    costs = []
    for seed in range(8):
        Gn = add_noise(G, sd, seed)
        start = fd_subspace(Gn, Z, 4, var=var)
        refined = fd_refine(*start, Gn, Z, var=var)
        assert pole_error(start[0], poles) < 3e-3
        assert pole_error(refined[0], poles) < 3e-3
        c0, c1 = weighted_cost(start, Gn, var), weighted_cost(refined, Gn, var)
        assert c1 <= c0 * (1 + 1e-12)
        assert c0 < 1.1 * c1
        costs.append(c1)
    assert np.mean(costs) == pytest.approx(K_LINES.size - 4.5, abs=14)


def test_weighting_helps_with_uneven_noise():
    """Every fourth line 100 times noisier than the rest (std 0.3 vs 0.003).
    Weighted by 1/sigma, those lines count for little and the poles are
    found from the clean ones: over 8 seeds the weighted pole error was
    10-90 times smaller than the unweighted one (asserted: 5 times in the
    mean), and the weighted fit is a chi-square of the right size (mean over
    8 seeds within 14 of 99 - 4.5, see above) while the unweighted one is
    ~100 times too large."""
    model, poles = make_system()
    G = frequency_response(*model, Z)
    sd = np.where(K_LINES % 4 == 0, 0.3, 0.003)[:, None, None] * np.ones(G.shape)
    errors, costs = [], []
    for seed in range(8):
        Gn = add_noise(G, sd, seed)
        weighted = fd_subspace(Gn, Z, 4, var=sd**2)
        plain = fd_subspace(Gn, Z, 4)
        errors.append([pole_error(weighted[0], poles), pole_error(plain[0], poles)])
        costs.append([weighted_cost(weighted, Gn, sd**2), weighted_cost(plain, Gn, sd**2)])
    errors, costs = np.array(errors), np.array(costs)
    assert np.mean(errors[:, 1]) > 5 * np.mean(errors[:, 0])
    assert np.mean(costs[:, 0]) == pytest.approx(K_LINES.size - 4.5, abs=14)
    assert np.mean(costs[:, 1]) > 10 * np.mean(costs[:, 0])


# --------------------------------------------------------------------------
# fd_refine and frf_weights
# --------------------------------------------------------------------------

def test_refine_recovers_exact_system_from_perturbed_start():
    """Exact data, start with every matrix perturbed by 1 %: LM converges to
    the true poles (the cost at the true system is zero)."""
    model, poles = make_system(seed=6)
    G = frequency_response(*model, Z)
    rng = np.random.default_rng(0)
    start = [M * (1 + 0.01 * rng.standard_normal(M.shape)) for M in model]
    assert is_stable(start[0]) and pole_error(start[0], poles) > 1e-3
    A, B, C, D = fd_refine(*start, G, Z, max_iter=200)
    assert pole_error(A, poles) < 1e-7
    np.testing.assert_allclose(frequency_response(A, B, C, D, Z), G, atol=1e-7)


def test_refine_is_equivariant_to_unit_changes():
    """The docstring's promise: rescaling the output by c (G -> c G, start's
    C, D -> c C, c D) or the input by 1/c (G -> c G, start's B, D -> c B,
    c D) gives the same A (same state basis) and scales only those
    matrices, because the weights (1 / rms G) and the column-scaled LM steps
    absorb c. Measured: equal to rounding (2e-16)."""
    model, poles = make_system(seed=7)
    G = add_noise(frequency_response(*model, Z), 0.01, seed=1)
    A0, B0, C0, D0 = fd_subspace(G, Z, 4)
    A1, B1, C1, D1 = fd_refine(A0, B0, C0, D0, G, Z)
    assert np.max(np.abs(A1 - A0)) > 1e-6  # the refinement does move
    c = 1e3
    A2, B2, C2, D2 = fd_refine(A0, B0, c * C0, c * D0, c * G, Z)
    np.testing.assert_allclose(A2, A1, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(B2, B1, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(C2, c * C1, rtol=1e-9, atol=1e-12 * c)
    np.testing.assert_allclose(D2, c * D1, rtol=1e-9, atol=1e-12 * c)
    A3, B3, C3, D3 = fd_refine(A0, c * B0, C0, c * D0, c * G, Z)
    np.testing.assert_allclose(A3, A1, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(B3, c * B1, rtol=1e-9, atol=1e-12 * c)
    np.testing.assert_allclose(C3, C1, rtol=1e-9, atol=1e-12)


def test_refine_keeps_start_when_it_cannot_improve():
    """At the exact system the cost is zero: nothing to improve, the start
    comes back unchanged."""
    model, _ = make_system(seed=8)
    G = frequency_response(*model, Z)
    out = fd_refine(*model, G, Z)
    for M, M0 in zip(out, model):
        np.testing.assert_allclose(M, M0, rtol=1e-12, atol=1e-14)


def test_frf_weights():
    rng = np.random.default_rng(9)
    G = rng.standard_normal((6, 1, 2)) + 1j * rng.standard_normal((6, 1, 2))
    rms = np.sqrt(np.mean(np.abs(G) ** 2))
    np.testing.assert_allclose(frf_weights(G, None), np.full(6, 1 / rms))
    # Weight 1/sigma from the mean variance over the entries of each line.
    var = np.array([1.0, 4.0, 0.25, 1.0, 4.0, 16.0])[:, None, None] * np.ones((6, 1, 2))
    np.testing.assert_allclose(frf_weights(G, var), [1.0, 0.5, 2.0, 1.0, 0.5, 0.25])
    # Lines without a usable variance (zero, NaN) get the median of the
    # usable ones; a tiny one is floored at 1e-6 of that median.
    var[2] = 0.0
    var[3] = np.nan
    var[5] = 1e-20
    w = frf_weights(G, var)
    median = np.median([1.0, 4.0, 4.0, 1e-20])  # usable: lines 0, 1, 4, 5
    np.testing.assert_allclose(w[[2, 3]], 1 / np.sqrt(median))
    np.testing.assert_allclose(w[5], 1 / np.sqrt(1e-6 * median))
    # No usable variance at all: back to the unweighted 1/rms.
    np.testing.assert_allclose(frf_weights(G, np.zeros((6, 1, 2))), np.full(6, 1 / rms))


# --------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------

def test_q_must_exceed_order():
    model, _ = make_system()
    G = frequency_response(*model, Z)
    with pytest.raises(ValueError, match="q must exceed"):
        fd_subspace(G, Z, 4, q=4)


def test_too_few_lines():
    model, _ = make_system()
    G = frequency_response(*model, Z)
    with pytest.raises(ValueError, match="Too few frequency lines"):
        fd_subspace(G[:10], Z[:10], 4, q=8)
