"""Decoupling start: Jacobian tensor, CPD, branch fit (pure functions)."""
import numpy as np
import pytest
import tensorly as tl

from sklearn_pnlss.decoupling import (
    CPDResult,
    branch_derivatives,
    decompose_jacobian,
    decoupled_map,
    evaluate_branches,
    fit_branches,
    polynomial_jacobian,
    polynomial_map,
    rank_scan,
    sample_points,
)
from sklearn_pnlss.statespace.monomials import monomial_exponents

N_OUT, N_VARS = 3, 4


def _random_polynomial(rng, degrees=(2, 3), n_out=N_OUT, n_vars=N_VARS):
    exponents = monomial_exponents(n_vars, degrees)
    E = rng.normal(size=(n_out, len(exponents)))
    return E, exponents


@pytest.fixture
def decoupled():
    """An exactly decoupled f(s) = W g(V^T s) with r = 2 branches.

    g_1(z) = 0.8 z^2 - 0.5 z^3 and g_2(z) = -0.3 z^2 + 0.7 z^3; written as a
    full polynomial E zeta(s) over all monomials of degrees 2 and 3 of four
    variables by an (exact) least-squares fit.
    """
    rng = np.random.default_rng(1)
    W = rng.normal(size=(N_OUT, 2))
    V = rng.normal(size=(N_VARS, 2))
    coef = np.array([[0.0, 0.8, -0.5], [0.0, -0.3, 0.7]])  # degrees 1..3, no linear term
    exponents = monomial_exponents(N_VARS, (2, 3))
    fit_points = rng.normal(size=(200, N_VARS))
    zeta = polynomial_map(np.eye(len(exponents)), exponents, fit_points)
    E = np.linalg.lstsq(zeta, decoupled_map(W, V, coef, fit_points), rcond=None)[0].T
    points = rng.normal(size=(300, N_VARS))
    return {
        "W": W,
        "V": V,
        "coef": coef,
        "E": E,
        "exponents": exponents,
        "points": points,
    }


# --- Jacobian tensor ---------------------------------------------------------


def test_polynomial_jacobian_matches_central_differences():
    rng = np.random.default_rng(0)
    E, exponents = _random_polynomial(rng)
    points = rng.normal(size=(50, N_VARS))
    J = polynomial_jacobian(E, exponents, points)
    assert J.shape == (N_OUT, N_VARS, 50)
    h = 1e-5
    for v in range(N_VARS):
        step = np.zeros(N_VARS)
        step[v] = h
        fd = (
            polynomial_map(E, exponents, points + step)
            - polynomial_map(E, exponents, points - step)
        ) / (2 * h)
        np.testing.assert_allclose(J[:, v, :], fd.T, rtol=1e-6, atol=1e-8)


def test_polynomial_jacobian_exact_at_zero_coordinates():
    # f = s0^2 s1 + 3 s1^3: exponents 0 must not produce 0 ** -1
    J = polynomial_jacobian([[1.0, 3.0]], [[2, 1], [0, 3]], [[0.0, 2.0], [1.0, 0.0]])
    np.testing.assert_array_equal(J[0], [[0.0, 0.0], [36.0, 1.0]])


def test_polynomial_map_and_jacobian_of_a_known_polynomial():
    # f = [s0 s1^2, 2 s0^3] at (2, 3)
    E = [[1.0, 0.0], [0.0, 2.0]]
    exponents = [[1, 2], [3, 0]]
    f = polynomial_map(E, exponents, [[2.0, 3.0]])
    np.testing.assert_allclose(f, [[18.0, 16.0]])
    J = polynomial_jacobian(E, exponents, [[2.0, 3.0]])[:, :, 0]
    np.testing.assert_allclose(J, [[9.0, 12.0], [24.0, 0.0]])


def test_sample_points_draws_rows_of_the_trajectory():
    trajectory = np.arange(60.0).reshape(30, 2)
    points = sample_points(trajectory, n_points=10, random_state=0)
    rows = points[:, 0] / 2
    assert points.shape == (10, 2)
    np.testing.assert_array_equal(points, trajectory[rows.astype(int)])
    assert len(np.unique(rows)) == 10  # without replacement
    np.testing.assert_array_equal(points, sample_points(trajectory, 10, random_state=0))
    # Generator accepted; fewer rows than points -> with replacement
    rng = np.random.default_rng(0)
    many = sample_points(trajectory, n_points=100, random_state=rng)
    assert many.shape == (100, 2)
    assert np.isin(many[:, 0], trajectory[:, 0]).all()


# --- CPD -----------------------------------------------------------------------


def _abs_cosines(A, B):
    """|cos| between the columns of A and of B (unit-normalised)."""
    A = A / np.linalg.norm(A, axis=0)
    B = B / np.linalg.norm(B, axis=0)
    return np.abs(A.T @ B)


def test_exactly_decoupled_map_is_recovered(decoupled):
    d = decoupled
    points = d["points"]
    J = polynomial_jacobian(d["E"], d["exponents"], points)
    # The full polynomial's Jacobian is the decoupled one: W diag(g') V^T.
    H_true = branch_derivatives(d["coef"], points @ d["V"])
    J_true = np.einsum("il,vl,kl->ivk", d["W"], d["V"], H_true)
    np.testing.assert_allclose(J, J_true, rtol=1e-9, atol=1e-9 * np.abs(J_true).max())

    W, V, H, error = decompose_jacobian(J, 2, random_state=0)
    assert error < 1e-8
    # V and W are the true directions up to order and scale (CPD uniqueness)
    for est, true in ((V, d["V"]), (W, d["W"])):
        cos = _abs_cosines(est, true)
        assert np.allclose(np.sort(cos.max(axis=1)), 1.0, atol=1e-9)
        assert sorted(cos.argmax(axis=1)) == [0, 1]

    coef = fit_branches(V, H, points, degree=3)
    assert coef.shape == (2, 3)
    np.testing.assert_array_equal(coef[:, 0], 0.0)
    new_points = np.random.default_rng(7).normal(size=(100, N_VARS))
    f_true = polynomial_map(d["E"], d["exponents"], new_points)
    f_dec = decoupled_map(W, V, coef, new_points)
    assert np.linalg.norm(f_dec - f_true) / np.linalg.norm(f_true) < 1e-8
    # a higher branch degree finds zero coefficients beyond degree 3
    coef5 = fit_branches(V, H, points, degree=5)
    np.testing.assert_allclose(coef5[:, :3], coef, rtol=1e-7, atol=1e-12)
    assert np.abs(coef5[:, 3:]).max() < 1e-7 * np.abs(coef).max()


def test_cpd_normalisation_convention():
    rng = np.random.default_rng(3)
    J = rng.normal(size=(N_OUT, N_VARS, 40))
    W, V, H, _ = decompose_jacobian(J, 3, random_state=0)
    for factor in (W, V):
        np.testing.assert_allclose(np.linalg.norm(factor, axis=0), 1.0)
        cols = np.arange(3)
        assert (factor[np.abs(factor).argmax(axis=0), cols] > 0).all()
    h_norms = np.linalg.norm(H, axis=0)
    assert (np.diff(h_norms) <= 0).all()


def _rank3_tensor():
    rng = np.random.default_rng(4)
    return np.einsum(
        "il,vl,kl->ivk",
        rng.normal(size=(N_OUT, 3)),
        rng.normal(size=(N_VARS, 3)),
        rng.normal(size=(60, 3)),
    )


def test_rank_scan_decreases_and_reaches_zero_at_true_rank():
    scan = rank_scan(_rank3_tensor(), [1, 2, 3], n_init=2, random_state=0)
    np.testing.assert_array_equal(scan.ranks, [1, 2, 3])
    assert scan.errors[0] > scan.errors[1] > scan.errors[2]
    assert scan.errors[1] > 1e-3  # rank 2 is genuinely too small
    assert scan.errors[2] < 1e-8
    assert scan.as_dict()[3] == scan.errors[2]


def test_exact_tensor_is_polished_below_tensorly_error_floor():
    # tensorly's own error estimate bottoms out near 1e-8; the polish phase
    # with the directly computed error must go well below it, every start.
    rng = np.random.default_rng(2)
    W, V = rng.normal(size=(N_OUT, 2)), rng.normal(size=(N_VARS, 2))
    points = rng.normal(size=(300, N_VARS))
    H = branch_derivatives(np.column_stack([np.zeros(2), rng.normal(size=(2, 2))]), points @ V)
    J = np.einsum("il,vl,kl->ivk", W, V, H)
    errors = [decompose_jacobian(J, 2, random_state=s).error for s in range(5)]
    assert max(errors) < 1e-9


def test_nearly_collinear_branches_are_recovered():
    # Two almost parallel columns of W (cos ~ 0.999, as happens with more
    # branches than outputs) put plain ALS in a long swamp: without the line
    # search all three starts were still at a relative error ~3e-3 after the
    # sweep budget. With it, the exact decomposition is found (the linear
    # convergence of the polish then stops it near 1e-8, hence 1e-6 here).
    rng = np.random.default_rng(5)
    w = rng.normal(size=N_OUT)
    W = np.column_stack([w, w + 0.15 * np.linalg.norm(w) * rng.normal(size=N_OUT)])
    V = rng.normal(size=(N_VARS, 2))
    points = rng.normal(size=(300, N_VARS))
    H = branch_derivatives([[0.0, 0.8, 0.3], [0.0, -0.7, 1.4]], points @ V)
    J = np.einsum("il,vl,kl->ivk", W, V, H)
    cos = abs(W[:, 0] @ W[:, 1]) / np.prod(np.linalg.norm(W, axis=0))
    assert cos > 0.998
    scan = rank_scan(J, [2], n_init=3, random_state=0)
    assert scan.errors[0] < 1e-6


def test_rank_above_tensor_rank_does_not_break_als():
    # extra terms die out: their Gram matrices go singular without a ridge
    rng = np.random.default_rng(5)
    J = np.einsum("i,v,k->ivk", *(rng.normal(size=n) for n in (N_OUT, N_VARS, 30)))
    result = decompose_jacobian(J, 4, random_state=0)
    assert isinstance(result, CPDResult)
    assert result.error < 1e-8


def test_cpd_reproducible_and_backend_untouched():
    J = _rank3_tensor()
    backend = tl.get_backend()
    a = decompose_jacobian(J, 2, random_state=0)
    b = decompose_jacobian(J, 2, random_state=np.int64(0))
    for x, y in zip(a[:3], b[:3], strict=True):
        np.testing.assert_array_equal(x, y)
    assert a.error == b.error
    g1 = decompose_jacobian(J, 2, random_state=np.random.default_rng(9))
    g2 = decompose_jacobian(J, 2, random_state=np.random.default_rng(9))
    np.testing.assert_array_equal(g1.V, g2.V)
    decompose_jacobian(J, 2, random_state=np.random.RandomState(0))
    assert tl.get_backend() == backend
    s1 = rank_scan(J, [1, 2], n_init=2, random_state=np.random.default_rng(2))
    s2 = rank_scan(J, [1, 2], n_init=2, random_state=np.random.default_rng(2))
    np.testing.assert_array_equal(s1.errors, s2.errors)
    assert tl.get_backend() == backend


def test_cpd_repeated_call_is_the_first_result_and_moves_the_random_state_alike(monkeypatch):
    # A grid over the branch degree decomposes the same tensor from the same
    # seeds once per degree: ALS runs once, and the answer is the one a fresh
    # run gives, the caller's RandomState ending where a fresh run leaves it.
    from sklearn_pnlss.decoupling import cpd

    runs = []
    als = cpd._alternating_least_squares
    monkeypatch.setattr(cpd, "_alternating_least_squares", lambda *args: runs.append(1) or als(*args))
    J = np.random.default_rng(41).normal(size=(N_OUT, N_VARS, 40))  # no exact CPD: ALS runs its sweeps
    first_state, again_state = np.random.RandomState(3), np.random.RandomState(3)
    first = decompose_jacobian(J, 2, random_state=first_state)
    first.W[:] = 0.0  # a caller writing into its factors changes nothing for the next
    again = decompose_jacobian(J, 2, random_state=again_state)
    by_int = decompose_jacobian(J, 2, random_state=3)  # tensorly's RandomState(3), the same start
    assert len(runs) == 1
    fresh_state = np.random.RandomState(3)
    fresh = als(J, 2, 2000, 1e-10, fresh_state)
    fresh_by_int = als(J, 2, 2000, 1e-10, 3)
    for kept in (again, by_int, fresh_by_int):
        for x, y in zip(kept, fresh, strict=True):
            np.testing.assert_array_equal(x, y)
    assert fresh.error > 1e-3  # a result ALS had to work for
    assert again_state.randint(2**31) == first_state.randint(2**31) == fresh_state.randint(2**31)
    decompose_jacobian(J, 2, random_state=None)
    decompose_jacobian(J, 3, random_state=3)
    assert len(runs) == 3  # no fixed start, or another rank: run anew


# --- branches ------------------------------------------------------------------


def test_fit_branches_drops_the_linear_term_and_handles_scale():
    # g(z) = 0.5 z^2 + 2 z^3 - z^4, plus a linear term 4 z of f (so g' has a
    # constant 4) that must be dropped without spoiling the others. z is in
    # the thousands: the internal rms scaling keeps the fit exact.
    rng = np.random.default_rng(6)
    points = 1e3 * rng.normal(size=(200, 2))
    v = np.array([[0.6], [0.8]])
    z = (points @ v)[:, 0]
    H = (4.0 + 1.0 * z + 6.0 * z**2 - 4.0 * z**3)[:, None]
    coef = fit_branches(v, H, points, degree=4)
    np.testing.assert_allclose(coef, [[0.0, 0.5, 2.0, -1.0]], rtol=1e-8)


@pytest.mark.parametrize("bounds, linear", [(None, False), ([[-0.5, 0.4], [-1.0, 1.0], [-0.2, 2.0]], False),
                                            ([[-0.5, 0.4], [-1.0, 1.0], [-0.2, 2.0]], True)])
def test_branch_values_and_derivatives_agree(bounds, linear):
    rng = np.random.default_rng(8)
    coef = rng.normal(size=(3, 5))  # degrees 1..5
    Z = rng.normal(size=(20, 3))
    h = 1e-6
    fd = (evaluate_branches(coef, Z + h, bounds, linear) - evaluate_branches(coef, Z - h, bounds, linear)) / (2 * h)
    np.testing.assert_allclose(branch_derivatives(coef, Z, bounds, linear), fd, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(evaluate_branches(coef, np.zeros((1, 3)), bounds, linear), 0.0)


@pytest.mark.parametrize("linear", [False, True])
def test_branch_evaluator_is_the_kernels_twin(linear):
    """One step of the compiled decoupled model from x = 0 with A = 0 and
    B = 0 gives x(1) = Wx g(V^T [0; u]): the kernel's branch values, outside
    the trusted range too, are the Python evaluator's."""
    from sklearn_pnlss.statespace.decoupled import DecoupledModel

    rng = np.random.default_rng(3)
    r, d, m = 3, 6, 3
    V = np.vstack([np.zeros((1, r)), np.eye(m)])  # z = u
    G = rng.normal(size=(r, d))
    bounds = np.array([[-0.5, 0.4], [-1.0, 1.0], [-0.2, 2.0]])
    model = DecoupledModel(
        A=np.zeros((1, 1)), B=np.zeros((1, m)), C=np.eye(1), D=np.zeros((1, m)), Wx=np.ones((1, r)),
        Wy=np.zeros((1, r)), V=V, G=G, bounds=bounds, linear_extrapolation=linear,
    )
    U = 1.5 * rng.normal(size=(40, m))  # about half the points outside the range
    x1 = np.array([model.simulate_states(np.vstack([u, np.zeros(m)]))[1, 0] for u in U])
    np.testing.assert_allclose(x1, evaluate_branches(G, U, bounds, linear).sum(axis=1), rtol=1e-12, atol=1e-12)


# --- validation ----------------------------------------------------------------


def test_bad_input_raises_value_error_naming_the_argument():
    rng = np.random.default_rng(0)
    E, exponents = _random_polynomial(rng)
    points = rng.normal(size=(10, N_VARS))
    J = polynomial_jacobian(E, exponents, points)
    with pytest.raises(ValueError, match="rank"):
        decompose_jacobian(J, 0)
    with pytest.raises(ValueError, match="ranks"):
        rank_scan(J, [1, 0])
    with pytest.raises(ValueError, match="exponents"):
        polynomial_jacobian(E[:, :-1], exponents, points)
    with pytest.raises(ValueError, match="exponents"):
        polynomial_jacobian(E, -exponents, points)
    with pytest.raises(ValueError, match="points"):
        polynomial_jacobian(E, exponents, points[:, :-1])
    bad = points.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="points"):
        polynomial_jacobian(E, exponents, bad)
    V, H = rng.normal(size=(N_VARS, 2)), rng.normal(size=(10, 2))
    with pytest.raises(ValueError, match="degree"):
        fit_branches(V, H, points, degree=1)
    with pytest.raises(ValueError, match="points"):
        fit_branches(V, H, bad, degree=3)
    with pytest.raises(ValueError, match="H"):
        fit_branches(V, H[:5], points, degree=3)
    with pytest.raises(ValueError, match="J"):
        decompose_jacobian(J[0], 1)
    with pytest.raises(ValueError, match="J"):
        decompose_jacobian(np.zeros_like(J), 1)
    with pytest.raises(ValueError, match="n_points"):
        sample_points(points, n_points=0)
    with pytest.raises(ValueError, match="coef"):
        decoupled_map(rng.normal(size=(N_OUT, 2)), V, np.ones((3, 3)), points)


def test_signed_branches_are_fitted_from_their_derivatives():
    """g(z) = z|z| + z**3 has g'(z) = 2|z| + 3z**2: in signed powers the
    fit recovers it exactly (in powers it cannot: |z| is no polynomial)."""
    z = np.linspace(-1.0, 1.0, 41)
    H = (2 * np.abs(z) + 3 * z**2)[:, None]
    coef = fit_branches([[1.0]], H, z[:, None], degree=3, signed=True)
    np.testing.assert_allclose(coef, [[0.0, 1.0, 1.0]], atol=1e-12)
    g = evaluate_branches(coef, z[:, None], signed=True)[:, 0]
    np.testing.assert_allclose(g, z * np.abs(z) + z**3, atol=1e-12)
    np.testing.assert_allclose(branch_derivatives(coef, z[:, None], signed=True)[:, 0], H[:, 0], atol=1e-12)
