"""Spline branches of the decoupled model: the basis, the compiled kernels
against their Python twins, the exact Jacobian, and the null directions."""
from dataclasses import replace

import numpy as np
import pytest

from sklearn_pnlss.decoupling import branch_derivatives, evaluate_branches
from sklearn_pnlss.statespace.decoupled import DecoupledModel, Segment
from sklearn_pnlss.statespace.splines import cubic_bspline_basis, greville_points, spline_knots
from jacobian_check import finite_difference_jacobian


def _spline_model(rng, n=3, m=1, p=1, r=2, d=7, output_branches=True):
    return DecoupledModel(
        A=np.diag(np.linspace(0.9, 0.3, n)) + 0.05 * rng.standard_normal((n, n)),
        B=0.5 * rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        Wx=0.2 * rng.standard_normal((n, r)), Wy=0.2 * rng.standard_normal((p, r)),
        V=rng.standard_normal((n + m, r)) / np.sqrt(n + m), G=0.3 * rng.standard_normal((r, d)),
        output_branches=output_branches,
        # knots over [-0.5, 0.5]: the inputs below cross both edges
        knots=np.tile([-0.5, 1.0 / (d - 3)], (r, 1)),
    )


def test_basis_reproduces_cubics_and_continues_along_tangents():
    knots, d = spline_knots([-2.0, 3.0], 9, margin=0.0), 9
    z = np.linspace(-2.0, 3.0, 41)
    B, dB = cubic_bspline_basis(z, knots, d)
    np.testing.assert_allclose(B.sum(axis=1), 1.0, atol=1e-13)  # partition of unity
    np.testing.assert_allclose(B @ greville_points(knots, d), z, atol=1e-12)  # linear functions exactly
    # a cubic is in the space: least squares on the basis fits it to round-off
    f = z**3 - 2 * z
    c = np.linalg.lstsq(B, f, rcond=None)[0]
    np.testing.assert_allclose(B @ c, f, atol=1e-10)
    np.testing.assert_allclose(dB @ c, 3 * z**2 - 2, atol=1e-9)
    # beyond the knots: the tangent at the edge
    out, _ = cubic_bspline_basis([4.0, -3.5], knots, d)
    np.testing.assert_allclose(out @ c, [f[-1] + 1.0 * (3 * 9 - 2), f[0] - 1.5 * (3 * 4 - 2)], atol=1e-9)


def test_kernel_simulation_equals_its_python_twin():
    rng = np.random.default_rng(0)
    model = _spline_model(rng)
    model.bounds = np.array([[-0.7, 0.6], [-0.4, 0.8]])
    U = 0.8 * rng.standard_normal((300, 1))
    for linear in (False, True):
        m = replace(model, linear_extrapolation=linear)
        Y, X = m.simulate(U)[0], m.trajectory([U])
        z = X @ m.V
        assert z.min() < -0.7 and z.max() > 0.8  # both continuations and the tangents are exercised
        g = evaluate_branches(m.G, z, m.bounds, linear, knots=m.knots)
        np.testing.assert_allclose(Y, X[:, :3] @ m.C.T + U @ m.D.T + g @ m.Wy.T, atol=1e-12)
        np.testing.assert_allclose(X[1:, :3], X[:-1, :3] @ m.A.T + U[:-1] @ m.B.T + g[:-1] @ m.Wx.T, atol=1e-12)


@pytest.mark.parametrize("linear_extrapolation", [False, True])
def test_jacobian_is_exact(linear_extrapolation):
    rng = np.random.default_rng(1)
    model = replace(_spline_model(rng, m=2, p=2), linear_extrapolation=linear_extrapolation,
                    bounds=np.array([[-0.6, 0.7], [-0.8, 0.5]]))
    U = 0.5 * rng.standard_normal((200, 2))
    seg = [Segment(U, np.zeros((190, 2)), 10)]
    J = model.jacobian(seg)
    J_fd = finite_difference_jacobian(model, seg)
    assert np.abs(J - J_fd).max() < 1e-6 * np.abs(J).max()


def test_branch_derivatives_are_the_slopes_of_the_branches():
    rng = np.random.default_rng(2)
    coef, knots = rng.standard_normal((2, 8)), np.array([[-1.0, 0.4], [0.0, 0.1]])
    z = np.column_stack([np.linspace(-2, 2, 50), np.linspace(-0.5, 1.0, 50)])
    h = 1e-6
    slope = (evaluate_branches(coef, z + h, knots=knots) - evaluate_branches(coef, z - h, knots=knots)) / (2 * h)
    np.testing.assert_allclose(branch_derivatives(coef, z, knots=knots), slope, atol=1e-7)
    np.testing.assert_allclose(evaluate_branches(coef, np.zeros((1, 2)), knots=knots), 0.0, atol=1e-14)


def test_null_directions_leave_the_output_unchanged():
    """Equal spline coefficients (a constant, cancelled by -B_k(0)) and a
    linear branch moved into A, B, C, D: both leave the simulation as is,
    which is what n_null_directions counts."""
    rng = np.random.default_rng(3)
    model = _spline_model(rng)
    U = 0.5 * rng.standard_normal((200, 1))
    y = model.simulate(U)[0]
    shifted = replace(model, G=model.G + 0.7)
    np.testing.assert_allclose(shifted.simulate(U)[0], y, atol=1e-12)
    c = 0.3
    line = c * np.vstack([greville_points(k, model.degree) for k in model.knots])
    moved = replace(model, G=model.G + line, A=model.A - c * model.Wx @ model.V[:3].T,
                    B=model.B - c * model.Wx @ model.V[3:].T, C=model.C - c * model.Wy @ model.V[:3].T,
                    D=model.D - c * model.Wy @ model.V[3:].T)
    np.testing.assert_allclose(moved.simulate(U)[0], y, atol=1e-10)
    assert model.n_null_directions == 9 + 3 * 2


def test_knots_are_checked():
    rng = np.random.default_rng(4)
    model = _spline_model(rng)
    with pytest.raises(ValueError, match="knots of shape"):
        replace(model, knots=np.ones((3, 2)))
    with pytest.raises(ValueError, match="at least 4 coefficients"):
        replace(model, G=model.G[:, :3])


# --- the estimator ---------------------------------------------------------

def _knee_system(n_realizations, seed):
    """A Wiener-Hammerstein system whose static nonlinearity has a knee
    (slope 1, then 0.1 above 0.4): what a polynomial follows only with
    ripple."""
    from scipy.signal import cheby1, lfilter

    from sklearn_pnlss.signals import multisine

    n = 512
    X, _ = multisine(n, fs=1.0, f_band=(0.002, 0.3), rms=2.0, n_periods=2, n_realizations=n_realizations,
                     random_state=seed)
    (b1, a1), (b2, a2) = cheby1(3, 0.5, 0.2), cheby1(3, 0.5, 0.25)

    def respond(x):  # periodic steady state: three periods, the last kept
        v = lfilter(b1, a1, np.tile(x, 3))
        return lfilter(b2, a2, np.where(v > 0.4, 0.4 + 0.1 * (v - 0.4), v))[-x.size:]

    return X, np.stack([respond(x[:, 0]) for x in X])[..., None], n


def test_spline_branch_follows_a_knee_that_a_polynomial_misses():
    from sklearn.pipeline import make_pipeline

    from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor

    X, y, n = _knee_system(3, 0)
    X_test, y_test, _ = _knee_system(1, 9)

    def relative_error(**kw):
        model = make_pipeline(BLAEstimator(6, period=n), DecoupledPNLSSRegressor(
            6, n_branches=1, init="random", n_init=1, output_branches=True, max_iter=60, random_state=0, **kw))
        model.fit(X, y)
        return np.sqrt(np.mean((model.predict(X_test) - y_test) ** 2)) / y_test.std(), model[-1]

    spline_error, spline = relative_error(n_knots=10, degree=3)  # started from random cubics
    poly_error, poly = relative_error(degree=12)
    assert spline.n_params_ == poly.n_params_  # the same budget: 12 coefficients per branch
    assert spline.coef_.shape == (1, 12) and spline.branch_knots_.shape == (1, 10) and poly.branch_knots_ is None
    assert spline_error < 0.01  # measured 0.002
    assert spline_error < 0.5 * poly_error  # measured 0.018 for the polynomial
    # started from random polynomials of degree 9, steep at the range's
    # edges, the spline stays near the linear model's plateau (measured 0.29)
    assert relative_error(n_knots=10, degree=9)[0] > 10 * spline_error
    np.testing.assert_allclose(np.diff(spline.branch_knots_), np.diff(spline.branch_knots_)[0, 0])  # evenly spaced
    z, g = spline.branch_values()
    assert np.all(np.isfinite(g)) and spline.summary().structure["knots"] == 10
