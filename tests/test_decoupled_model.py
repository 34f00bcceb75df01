"""DecoupledModel: exact Jacobian, parameter blocks, divergence guard,
equivalence with the expanded PNLSS polynomial, and the CPD start."""
import time

import numpy as np
import pytest

from sklearn_pnlss.decoupling import evaluate_branches, polynomial_map
from sklearn_pnlss.decoupling.start import decoupled_start
from sklearn_pnlss.statespace.decoupled import DecoupledModel, DivergenceError, Segment
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel
from jacobian_check import finite_difference_jacobian


def _random_model(rng, n=3, m=1, p=1, r=2, d=4, output_branches=False, linear_branch=True, signed=False):
    G = 0.3 * rng.standard_normal((r, d)) / np.arange(1, d + 1)
    if not linear_branch:
        G[:, 0] = 0.0
    return DecoupledModel(
        A=np.diag(np.linspace(0.9, 0.3, n)) + 0.05 * rng.standard_normal((n, n)),
        B=0.5 * rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        Wx=0.2 * rng.standard_normal((n, r)),
        Wy=0.2 * rng.standard_normal((p, r)) if output_branches else np.zeros((p, r)),
        V=rng.standard_normal((n + m, r)) / np.sqrt(n + m),
        G=G, output_branches=output_branches, signed=signed,
    )


def _branch_map(W, V, G, S):
    """W g(V^T s) at the rows of S, with G over degrees 1..d."""
    Z = S @ V
    powers = np.arange(1, G.shape[1] + 1)
    return np.einsum("klp,lp->kl", Z[:, :, None] ** powers, G) @ W.T


def _expand(W, V, G, degrees, rng):
    """Coefficients over monomial_exponents(n_vars, degrees) of W g(V^T s),
    by least squares on random points (exact: the monomials span it)."""
    ex = monomial_exponents(V.shape[0], degrees)
    S = rng.standard_normal((4 * len(ex) + 50, V.shape[0]))
    zeta = polynomial_map(np.eye(len(ex)), ex, S)
    coef = np.linalg.lstsq(zeta, _branch_map(W, V, G, S), rcond=None)[0]
    return coef.T.copy(), ex


def _as_pnlss(model, rng, linear_branch=True):
    d = model.G.shape[1]
    degrees = range(1 if linear_branch else 2, d + 1)
    n_vars = model.V.shape[0]
    E, exE = _expand(model.Wx, model.V, model.G, degrees, rng)
    if model.output_branches:
        F, exF = _expand(model.Wy, model.V, model.G, degrees, rng)
    else:
        F, exF = np.zeros((model.C.shape[0], 0)), np.zeros((0, n_vars), dtype=np.int64)
    return PNLSSModel(A=model.A.copy(), B=model.B.copy(), C=model.C.copy(), D=model.D.copy(),
                      E=E, F=F, exE=exE, exF=exF)


@pytest.mark.parametrize("n, m, p", [(3, 1, 1), (3, 2, 2)])
@pytest.mark.parametrize("output_branches", [False, True])
@pytest.mark.parametrize("signed", [False, True])
def test_jacobian_is_exact(n, m, p, output_branches, signed):
    rng = np.random.default_rng(0)
    model = _random_model(rng, n=n, m=m, p=p, output_branches=output_branches, signed=signed)
    U = 0.3 * rng.standard_normal((200, m))
    seg = [Segment(U, np.zeros((190, p)), 10)]
    J = model.jacobian(seg)
    theta = model.theta
    assert J.shape == (190 * p, theta.size)
    J_fd = finite_difference_jacobian(model, seg)
    assert np.abs(J - J_fd).max() < 1e-6 * np.abs(J).max()
    # every block really moves the output (no silently zero column block)
    assert np.all(np.abs(J).max(axis=0) > 0)


def test_jacobian_without_transient_matches_segment_jacobian():
    rng = np.random.default_rng(1)
    model = _random_model(rng, output_branches=True)
    U = 0.3 * rng.standard_normal((100, 1))
    J0 = model.segment_jacobian(Segment(U, np.zeros((100, 1)), 0))
    J5 = model.segment_jacobian(Segment(U, np.zeros((95, 1)), 5))
    np.testing.assert_array_equal(J0[5:], J5)


@pytest.mark.parametrize("output_branches, n_params, n_nonlinear", [(False, 67, 51), (True, 70, 54)])
def test_parameter_counts(output_branches, n_params, n_nonlinear):
    model = _random_model(np.random.default_rng(0), n=3, m=1, p=1, r=3, d=10, output_branches=output_branches)
    assert model.n_nonlinear_params == n_nonlinear
    assert model.n_params == n_params == model.theta.size
    n, m, r, d = 3, 1, 3, 10
    if not output_branches:
        assert model.n_nonlinear_params == (2 * n + d + 1) * r
    assert model.n_nonlinear_params == (2 * n + m + d) * r + output_branches * r
    names = ("A", "B", "Wx", "V", "G", "C", "D") + (("Wy",) if output_branches else ())
    assert model._block_names == names


@pytest.mark.parametrize("output_branches", [False, True])
def test_with_theta_round_trip(output_branches):
    rng = np.random.default_rng(2)
    model = _random_model(rng, n=3, m=2, p=2, r=3, d=5, output_branches=output_branches)
    np.testing.assert_array_equal(model.with_theta(model.theta).theta, model.theta)
    theta = rng.standard_normal(model.n_params)
    new = model.with_theta(theta)
    np.testing.assert_array_equal(new.theta, theta)
    assert new.output_branches is output_branches
    # block order: A, B, Wx, V, G, C, D (, Wy)
    np.testing.assert_array_equal(new.A.ravel(), theta[:9])
    np.testing.assert_array_equal(new.B.ravel(), theta[9:15])
    np.testing.assert_array_equal(new.G.ravel(), theta[15 + 9 + 15 : 15 + 9 + 15 + 15])
    if output_branches:
        np.testing.assert_array_equal(new.Wy.ravel(), theta[-6:])
    else:
        np.testing.assert_array_equal(new.Wy, model.Wy)  # fixed, not a parameter
        assert not np.shares_memory(new.Wy, theta)
    copy = model.copy()
    assert copy.output_branches is output_branches
    np.testing.assert_array_equal(copy.theta, model.theta)


def test_shapes_are_checked():
    model = _random_model(np.random.default_rng(0))
    with pytest.raises(ValueError, match="V must have shape"):
        DecoupledModel(model.A, model.B, model.C, model.D, model.Wx, model.Wy, model.V[:-1], model.G)


def test_divergence_guard():
    rng = np.random.default_rng(3)
    model = _random_model(rng, linear_branch=False)
    model.G = 10.0 * np.abs(model.G) + 1.0
    U = 3.0 * np.ones((500, 1))
    seg = Segment(U, np.zeros((500, 1)), 0)
    assert model.segment_error(seg) is None
    assert model.residual([seg]) is None
    with pytest.raises(DivergenceError):
        model.simulate(U)


@pytest.mark.parametrize("n, m, p", [(3, 1, 1), (3, 2, 2)])
@pytest.mark.parametrize("output_branches", [False, True])
def test_same_output_as_the_expanded_pnlss(n, m, p, output_branches):
    rng = np.random.default_rng(4)
    model = _random_model(rng, n=n, m=m, p=p, r=3, d=4, output_branches=output_branches)
    model.G[:, 0] *= 0.3  # a stable linearisation
    model.G[:, 2:] *= 0.3  # bounded on this input
    pnlss = _as_pnlss(model, rng)
    U = 0.3 * rng.standard_normal((1000, m))
    Y, x_end = model.simulate(U)
    Y_ref, x_ref = pnlss.simulate(U)
    assert np.abs(Y - Y_ref).max() < 1e-10 * np.abs(Y_ref).max()
    np.testing.assert_allclose(model.simulate_states(U), pnlss.simulate_states(U), rtol=0, atol=1e-10)
    np.testing.assert_allclose(x_end, x_ref, rtol=0, atol=1e-10)
    # the nonlinearity really matters on this signal
    linear = DecoupledModel(model.A, model.B, model.C, model.D, 0 * model.Wx, 0 * model.Wy, model.V, model.G)
    assert np.abs(linear.simulate(U)[0] - Y).max() > 1e-3 * np.abs(Y).max()


def _one_step_jacobian(model, eps=1e-6):
    """d x(1) / d x(0) at rest, by central differences of one step."""
    n, m = model.n_states, model.B.shape[1]
    columns = []
    for j in range(n):
        step = eps * np.eye(n)[j]
        ahead, behind = (model.simulate_states(np.zeros((2, m)), x0=sign * step)[1] for sign in (1, -1))
        columns.append((ahead - behind) / (2 * eps))
    return np.column_stack(columns)


@pytest.mark.parametrize("signed", [False, True])
def test_state_matrix_at_rest_is_the_step_jacobian_at_rest(signed):
    rng = np.random.default_rng(8)
    model = _random_model(rng, n=4, m=2, p=2, r=3, d=4, signed=signed)
    at_rest = model.state_matrix_at_rest()
    # the branches' linear terms add to A (the higher powers vanish at rest)
    np.testing.assert_allclose(at_rest, model.A + model.Wx @ np.diag(model.G[:, 0]) @ model.V[:4].T, atol=1e-14)
    assert np.abs(at_rest - model.A).max() > 1e-2
    np.testing.assert_allclose(at_rest, _one_step_jacobian(model), atol=1e-8)
    if not signed:  # the same model written as a polynomial with its degree-1 monomials
        np.testing.assert_allclose(_as_pnlss(model, rng).state_matrix_at_rest(), at_rest, atol=1e-10)
    # a stable A whose branch slope at rest moves a pole past the unit circle
    model.A = np.diag([0.9, 0.5, 0.4, 0.3])
    model.Wx[:] = 0.0
    model.Wx[0, 0], model.V[:, 0], model.G[0, 0] = 1.0, np.eye(6)[0], 0.2  # x1(t+1) = 1.1 x1 + ...
    assert np.max(np.abs(np.linalg.eigvals(model.A))) < 1 and not model.stable_at_rest()
    model.G[0, 0] = 0.05
    assert model.stable_at_rest()


@pytest.mark.parametrize("output_branches, linear_in_E", [(False, False), (True, False), (False, True)])
def test_start_recovers_an_exactly_decoupled_pnlss(output_branches, linear_in_E):
    rng = np.random.default_rng(5)
    truth = _random_model(rng, n=3, m=1, p=1, r=2, d=3, output_branches=output_branches, linear_branch=linear_in_E)
    truth.G[:, 0] *= 0.3
    truth.Wx *= 3
    # linear_in_E: E also holds degree-1 monomials, which the start moves to A, B
    pnlss = _as_pnlss(truth, rng, linear_branch=linear_in_E)
    U = 0.5 * rng.standard_normal((2000, 1))
    S = np.hstack([pnlss.simulate_states(U), U])
    start, cpd_error = decoupled_start(pnlss, S, 2, 3, random_state=0)
    assert cpd_error < 1e-6
    assert isinstance(start, DecoupledModel)
    assert start.output_branches is output_branches
    assert start.G.shape == (2, 3)
    np.testing.assert_array_equal(start.G[:, 0], 0.0)
    assert not np.shares_memory(start.A, pnlss.A)
    if linear_in_E:
        A_lin = truth.A + truth.Wx @ np.diag(truth.G[:, 0]) @ truth.V[:3].T
        np.testing.assert_allclose(start.A, A_lin, rtol=0, atol=1e-10)
    else:
        np.testing.assert_array_equal(start.A, pnlss.A)
    # W g(V^T s) reproduces f's nonlinear part on the trajectory
    nonlinear = pnlss.exE.sum(axis=1) >= 2
    f = polynomial_map(pnlss.E[:, nonlinear], pnlss.exE[nonlinear], S)
    f_start = evaluate_branches(start.G, S @ start.V) @ start.Wx.T
    assert np.abs(f - f_start).max() < 1e-6 * np.abs(f).max()
    Y_ref = pnlss.simulate(U)[0]
    Y = start.simulate(U)[0]
    assert np.abs(Y - Y_ref).max() < 1e-6 * np.abs(Y_ref).max()


def test_spline_start_reproduces_the_cpd_branches():
    """The CPD start with spline branches: cubic splines hold the cubic
    branches exactly over their knots, so W g(V^T s) is the same map."""
    rng = np.random.default_rng(5)
    truth = _random_model(rng, n=3, m=1, p=1, r=2, d=3, linear_branch=False)
    pnlss = _as_pnlss(truth, rng, linear_branch=False)
    U = 0.5 * rng.standard_normal((2000, 1))
    S = np.hstack([pnlss.simulate_states(U), U])
    poly, _ = decoupled_start(pnlss, S, 2, 3, random_state=0)
    spline, _ = decoupled_start(pnlss, S, 2, 3, n_knots=6, random_state=0)
    assert spline.G.shape == (2, 8) and spline.knots.shape == (2, 2)
    Z = S @ spline.V
    inside = np.all((Z > spline.knots[:, 0]) & (Z < spline.knots[:, 0] + 5 * spline.knots[:, 1]), axis=1)
    assert inside.mean() > 0.9
    f_poly = evaluate_branches(poly.G, Z[inside]) @ poly.Wx.T
    f_spline = evaluate_branches(spline.G, Z[inside], knots=spline.knots) @ spline.Wx.T
    assert np.abs(f_spline - f_poly).max() < 1e-9 * np.abs(f_poly).max()


def test_start_validates_its_inputs():
    rng = np.random.default_rng(6)
    truth = _random_model(rng, r=2, d=3, linear_branch=False)
    pnlss = _as_pnlss(truth, rng, linear_branch=False)
    with pytest.raises(ValueError, match="columns"):
        decoupled_start(pnlss, np.zeros((100, 3)), 2, 3)
    with pytest.raises(ValueError, match="degree"):
        decoupled_start(pnlss, np.zeros((100, 4)), 2, 1)


def test_jacobian_speed_sanity():
    """Not a timing assert: one Jacobian of T = 8192, n = 3, r = 3, d = 10."""
    rng = np.random.default_rng(7)
    model = _random_model(rng, n=3, m=1, p=1, r=3, d=10)
    model.G *= 0.1
    U = 0.3 * rng.standard_normal((8192, 1))
    seg = Segment(U, np.zeros((8192, 1)), 0)
    model.segment_jacobian(seg)  # compile / load from cache
    t0 = time.perf_counter()
    J = model.segment_jacobian(seg)
    elapsed = time.perf_counter() - t0
    print(f"decoupled Jacobian T=8192, n=3, r=3, d=10: {1e3 * elapsed:.2f} ms")
    assert J.shape == (8192, 1, model.n_params)
    assert np.all(np.isfinite(J))


def test_step_basis_steps_the_branches_in_legendre_polynomials_over_their_range():
    """Each branch's coefficient steps are Legendre polynomials of z / c
    (c: the largest |z| at the points) less their value at 0; the other
    blocks are stepped as they are. Over the points, the scaled columns of
    the branch regression are far better conditioned than the powers (300 times here)."""
    from numpy.polynomial import legendre

    rng = np.random.default_rng(4)
    model = _random_model(rng, r=2, d=11)
    S = rng.uniform(-1, 1, (400, 4)) * [3.0, 0.1, 0.1, 0.1]  # z nearly uniform
    basis = model.step_basis(S)
    start = model.A.size + model.B.size + model.Wx.size + model.V.size
    G_block = slice(start, start + model.G.size)
    outside = np.ones(model.n_params, bool)
    outside[G_block] = False
    np.testing.assert_array_equal(basis[np.ix_(outside, outside)], np.eye(outside.sum()))
    assert not basis[np.ix_(outside, ~outside)].any() and not basis[np.ix_(~outside, outside)].any()

    Z = S @ model.V
    for branch in range(2):
        z, c = Z[:, branch], np.abs(Z[:, branch]).max()
        block = basis[G_block, G_block][branch * 11:(branch + 1) * 11, branch * 11:(branch + 1) * 11]
        powers = z[:, None] ** np.arange(1, 12)
        stepped = powers @ block  # column k - 1: the branch stepped along coefficient k
        for k in (1, 4, 11):
            P_k = np.eye(k + 1)[k]
            np.testing.assert_allclose(stepped[:, k - 1], legendre.legval(z / c, P_k) - legendre.legval(0, P_k),
                                       atol=1e-9)

        def cond(M):
            return np.linalg.cond(M / np.linalg.norm(M, axis=0))
        assert cond(stepped) * 100 < cond(powers)


def test_signed_powers_simulate_the_odd_branches():
    """In signed powers a branch is sum_k G[k] z |z|**k: the kernel's
    simulation equals a plain loop over the samples with that branch, and
    differs from the same coefficients in powers (the even terms change
    sign with z)."""
    rng = np.random.default_rng(7)
    model = _random_model(rng, n=3, m=1, p=1, r=2, d=4, signed=True)
    U = 0.5 * rng.standard_normal((300, 1))
    x, Y_ref = np.zeros(3), []
    for u in U:
        z = np.concatenate([x, u]) @ model.V
        g = np.array([sum(model.G[l, k] * z[l] * abs(z[l]) ** k for k in range(4)) for l in range(2)])
        Y_ref.append(model.C @ x + model.D @ u)
        x = model.A @ x + model.B @ u + model.Wx @ g
    Y, _ = model.simulate(U)
    np.testing.assert_allclose(Y, np.array(Y_ref), rtol=1e-12, atol=1e-12)
    z = np.array([[-1.5, 0.7]])
    assert np.allclose(evaluate_branches(model.G, z, signed=True), [[
        sum(model.G[l, k] * z[0, l] * abs(z[0, l]) ** k for k in range(4)) for l in range(2)]])
    plain = _random_model(np.random.default_rng(7), n=3, m=1, p=1, r=2, d=4)
    assert np.abs(plain.simulate(U)[0] - Y).max() > 1e-3 * np.abs(Y).max()
    with pytest.raises(ValueError, match="signed powers are a polynomial basis"):
        DecoupledModel(**{**{k: getattr(model, k) for k in "A B C D Wx Wy V".split()},
                          "G": np.zeros((2, 5)), "knots": np.ones((2, 2)), "signed": True})


@pytest.mark.parametrize("linear, signed", [(False, False), (True, False), (True, True)])
def test_simulation_continues_the_branches_past_their_range(linear, signed):
    """Past its trusted range a branch is held at its edge value, or
    continued along its edge tangent: the kernel's simulation (which
    computes a branch's derivative only there) equals a plain loop over the
    samples with ``evaluate_branches``, and the range is left often."""
    from dataclasses import replace

    rng = np.random.default_rng(11)
    model = _random_model(rng, n=3, m=1, p=2, r=3, d=5, output_branches=True, signed=signed)
    U = 0.8 * rng.standard_normal((400, 1))
    inside = model.simulate_states(0.5 * U)
    model = replace(model.with_trusted_range(np.hstack([inside, 0.5 * U])), linear_extrapolation=linear)
    x, Y_ref, left = np.zeros(3), [], 0
    for u in U:
        z = np.concatenate([x, u]) @ model.V
        left += bool(np.any((z < model.bounds[:, 0]) | (z > model.bounds[:, 1])))
        g = evaluate_branches(model.G, z[None], model.bounds, linear, signed=signed)[0]
        Y_ref.append(model.C @ x + model.D @ u + model.Wy @ g)
        x = model.A @ x + model.B @ u + model.Wx @ g
    Y, _ = model.simulate(U)
    assert left > 100  # the continuation is what is tested
    np.testing.assert_allclose(Y, np.array(Y_ref), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("splines", [False, True])
def test_branches_over_the_states_alone_hold_the_input_rows_of_v(splines):
    """``input_directions=False``: the input rows of V are zero and no step
    moves them (the step basis leaves their columns out), and they are not
    counted as parameters."""
    rng = np.random.default_rng(5)
    model = _random_model(rng, n=3, m=2, p=1, r=2, d=6)
    V = model.V.copy()
    V[3:] = 0.0
    knots = np.array([[-2.0, 0.5], [-2.0, 0.5]]) if splines else None
    held = DecoupledModel(model.A, model.B, model.C, model.D, model.Wx, model.Wy, V, model.G, knots=knots,
                          input_directions=False)
    assert held.n_fixed_params == 4 and held.n_nonlinear_params == model.n_nonlinear_params - 4
    basis = held.step_basis(rng.standard_normal((50, 5)))
    assert basis.shape == (held.n_params, held.n_params - 4)
    step = basis @ rng.standard_normal(basis.shape[1])
    moved = held.with_theta(held.theta + step)
    assert not moved.V[3:].any() and moved.V[:3].all()
    with pytest.raises(ValueError, match="input rows of V must be zero"):
        DecoupledModel(model.A, model.B, model.C, model.D, model.Wx, model.Wy, model.V, model.G,
                       input_directions=False)
