"""statespace/levenberg_marquardt.py on its own: known least-squares
problems, the dropped directions, diverging trial steps."""
import numpy as np
import pytest

from sklearn_pnlss.statespace.levenberg_marquardt import levenberg_marquardt, lm_step_basis


def _normal_equations(jacobian, residual):
    def normal_equations(theta):
        J, e = jacobian(theta), residual(theta)
        return J.T @ J, J.T @ e
    return normal_equations


def test_exponential_decay_is_fitted_exactly():
    """y = a exp(-b t) + c from noise-free samples: LM reaches the true
    (a, b, c) from a start 50 % off, the cost falls to rounding."""
    t = np.linspace(0, 4, 60)
    truth = np.array([2.0, 1.3, -0.4])

    def model(th):
        return th[0] * np.exp(-th[1] * t) + th[2]

    y = model(truth)

    def residual(th):
        return model(th) - y

    def jacobian(th):
        return np.column_stack([np.exp(-th[1] * t), -th[0] * t * np.exp(-th[1] * t), np.ones_like(t)])

    result = levenberg_marquardt(residual, _normal_equations(jacobian, residual), truth * [1.5, 0.5, 1.5],
                                 max_iter=100, tol=0.0)
    np.testing.assert_allclose(result.theta, truth, rtol=1e-10)
    assert result.cost < 1e-25
    costs = [c for _, c, _ in result.history]
    assert all(b <= a for a, b in zip(costs, costs[1:]))  # only improving iterates are accepted


def test_a_linear_problem_reaches_the_least_squares_solution():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((40, 5))
    b = rng.standard_normal(40)
    lstsq = np.linalg.lstsq(A, b, rcond=None)[0]
    result = levenberg_marquardt(lambda th: A @ th - b, lambda th: (A.T @ A, A.T @ (A @ th - b)), np.zeros(5),
                                 max_iter=50, tol=0.0)
    np.testing.assert_allclose(result.theta, lstsq, rtol=1e-8, atol=1e-9)


def test_dropped_directions_leave_the_redundant_parameter_alone():
    """y = (p + q) x depends on p + q only: with the null direction dropped,
    every step is orthogonal to it, so p - q keeps its start value."""
    x = np.linspace(-1, 1, 30)
    y = 3.0 * x

    def residual(th):
        return (th[0] + th[1]) * x - y

    def normal_equations(th):
        J = np.column_stack([x, x])
        return J.T @ J, J.T @ residual(th)

    result = levenberg_marquardt(residual, normal_equations, np.array([0.5, -0.2]), n_drop=1, max_iter=20)
    assert result.theta.sum() == pytest.approx(3.0, rel=1e-10)
    assert result.theta[0] - result.theta[1] == pytest.approx(0.7, rel=1e-12)


def test_step_basis_drops_the_smallest_singular_values():
    rng = np.random.default_rng(1)
    J = rng.standard_normal((50, 4)) * [1.0, 10.0, 100.0, 1e-3]
    scale, S, V = lm_step_basis(J.T @ J, n_drop=1)
    np.testing.assert_allclose(scale, np.linalg.norm(J, axis=0), rtol=1e-12)
    S_full = np.linalg.svd(J / scale, compute_uv=False)
    np.testing.assert_allclose(S, S_full[:3], rtol=1e-9)
    assert V.shape == (4, 3)


def test_a_diverging_trial_step_is_rejected_and_a_diverging_start_refused():
    """Trial points beyond theta = 2 'diverge' (residual None): LM must not
    return one, and must stop at the best point it could reach."""
    def residual(th):
        return None if th[0] > 2.0 else np.array([th[0] - 3.0])

    def normal_equations(th):
        return np.array([[1.0]]), np.array([th[0] - 3.0])

    result = levenberg_marquardt(residual, normal_equations, np.array([0.0]), max_iter=200)
    assert result.theta[0] <= 2.0
    assert result.theta[0] > 1.9  # it creeps up to the edge with growing lambda
    with pytest.raises(ValueError, match="starting model diverges"):
        levenberg_marquardt(residual, normal_equations, np.array([2.5]))


def test_a_well_conditioned_basis_reaches_the_optimum_in_fewer_steps():
    """A degree-11 polynomial fitted to samples on [-1, 1]: in powers of t
    the scaled columns are nearly collinear (condition number above 1e3),
    and the damping, halved each step from the largest singular value, needs
    many steps to free the smallest. Solved in Legendre polynomials (the same
    model, ``basis`` maps their coefficients to the powers') the columns are
    nearly orthogonal and a few steps reach the least-squares fit."""
    from numpy.polynomial import legendre

    t = np.linspace(-1, 1, 200)
    y = np.abs(t) + 0.3 * np.sin(4 * t)  # a kink: every degree is needed
    powers = np.column_stack([t**k for k in range(12)])
    best = np.linalg.lstsq(powers, y, rcond=None)[0]
    basis = np.zeros((12, 12))  # column k: the power coefficients of P_k
    for k in range(12):
        basis[: k + 1, k] = legendre.leg2poly(np.eye(k + 1)[k])

    def residual(th):
        return powers @ th - y

    def normal_equations(th):
        return powers.T @ powers, powers.T @ residual(th)

    def excess(**kwargs):
        result = levenberg_marquardt(residual, normal_equations, np.zeros(12), max_iter=8, tol=0.0, **kwargs)
        return result.cost / np.sum(residual(best) ** 2) - 1

    assert np.linalg.cond(powers / np.linalg.norm(powers, axis=0)) > 1e3
    assert excess(basis=basis) < 1e-6
    assert excess() > 1e-2


@pytest.mark.parametrize("damping, ratio", [("nielsen", 1 / np.sqrt(3)), ("toolbox", 1 / 2)])
def test_the_damping_falls_by_the_rule_on_a_model_that_is_exact(damping, ratio):
    """On a linear problem the linearised model predicts each step's fall
    exactly (rho = 1): Nielsen's rule divides mu = lambda^2 by 3, the
    toolbox's divides lambda by 2."""
    rng = np.random.default_rng(2)
    A = rng.standard_normal((40, 6)) * np.logspace(0, 3, 6)
    b = rng.standard_normal(40)
    result = levenberg_marquardt(lambda th: A @ th - b, lambda th: (A.T @ A, A.T @ (A @ th - b)), np.zeros(6),
                                 max_iter=6, tol=0.0, damping=damping)
    lams = np.array([lam for _, _, lam in result.history[1:]])
    np.testing.assert_allclose(lams[1:] / lams[:-1], ratio, rtol=1e-9)


def test_a_failed_step_costs_a_factor_that_doubles_with_each_failure_in_a_row():
    """Trial points beyond theta = 0.9 'diverge': from 0 with lambda equal
    to the singular value the first step (to 1.5) fails, mu is multiplied by
    2 (step to 1.0, fails), then by 4; the first accepted step is below 0.9."""
    def residual(th):
        return None if th[0] > 0.9 else np.array([th[0] - 3.0])

    def normal_equations(th):
        return np.array([[1.0]]), np.array([th[0] - 3.0])

    result = levenberg_marquardt(residual, normal_equations, np.array([0.0]), max_iter=1)
    # mu = 1 * 2 * 4 = 8 after two failures: step 3 / (1 + 8) = 1/3.
    assert result.theta[0] == pytest.approx(1 / 3, rel=1e-12)
    with pytest.raises(ValueError, match="damping must be"):
        levenberg_marquardt(residual, normal_equations, np.array([0.0]), damping="fast")


def test_the_cholesky_step_is_the_eigen_step_and_keeps_null_directions_still():
    """Without dropped directions both solvers give the same damped step and
    predicted fall at every damping, and nearly the same largest eigenvalue
    (the first damping); with an exact null direction (y depends on p + q
    only) the Cholesky step has no component along it either."""
    from sklearn_pnlss.statespace.levenberg_marquardt import _CholeskySteps, _EigenSteps

    rng = np.random.default_rng(3)
    J = rng.standard_normal((40, 6)) * np.logspace(0, 3, 6)
    G, g = J.T @ J, J.T @ rng.standard_normal(40)
    eigen, cholesky = _EigenSteps(G, g, 0), _CholeskySteps(G, g)
    assert cholesky.largest == pytest.approx(eigen.largest, rel=2e-2)  # power iteration: sets the damping only
    for mu in eigen.largest * np.logspace(-8, 2, 6):
        np.testing.assert_allclose(cholesky.step(mu), eigen.step(mu), rtol=1e-8)
        assert cholesky.predicted_fall(mu) == pytest.approx(eigen.predicted_fall(mu), rel=1e-10)

    x = np.linspace(-1, 1, 30)

    def residual(th):
        return (th[0] + th[1]) * x - 3.0 * x

    def normal_equations(th):
        J = np.column_stack([x, x])
        return J.T @ J, J.T @ residual(th)

    result = levenberg_marquardt(residual, normal_equations, np.array([0.5, -0.2]), max_iter=20, solver="cholesky")
    assert result.theta.sum() == pytest.approx(3.0, rel=1e-8)
    assert result.theta[0] - result.theta[1] == pytest.approx(0.7, rel=1e-10)
    with pytest.raises(ValueError, match="solver must be"):
        levenberg_marquardt(residual, normal_equations, np.array([0.0, 0.0]), solver="qr")


@pytest.mark.parametrize("n_params, n_rows, expected", [
    (300, 1000, "_EigenSteps"),        # small: the eigendecomposition is cheap outright
    (1000, 100_000, "_EigenSteps"),    # large, but under a quarter of the Gram matrix
    (1000, 10_000, "_CholeskySteps"),  # large beside the data
])
def test_auto_solver_keeps_the_eigendecomposition_where_it_is_cheap(n_params, n_rows, expected):
    from sklearn_pnlss.statespace.levenberg_marquardt import _steps

    G, g = np.eye(n_params), np.ones(n_params)
    assert type(_steps(G, g, 0, "auto", n_rows)).__name__ == expected
