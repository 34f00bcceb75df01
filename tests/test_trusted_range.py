"""The trusted range of a model's nonlinearity: outside the range its
variables covered in training, the polynomial is held at the edge (or, for
the decoupled branches, continued along the edge tangent). Inside, nothing
changes; outside, a stable linear part bounds the state for every bounded
input; and the Jacobian stays exact."""
from dataclasses import replace

import numpy as np
import pytest

from sklearn_pnlss.statespace.decoupled import DecoupledModel
from sklearn_pnlss.statespace.model_base import DivergenceError, Segment
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel


def _decoupled(rng, n=3, m=1, p=1, r=2, d=6, output_branches=True):
    return DecoupledModel(
        A=np.diag(np.linspace(0.9, 0.3, n)) + 0.02 * rng.standard_normal((n, n)),
        B=0.5 * rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        Wx=0.2 * rng.standard_normal((n, r)), Wy=0.2 * rng.standard_normal((p, r)),
        V=rng.standard_normal((n + m, r)) / np.sqrt(n + m),
        G=0.3 * rng.standard_normal((r, d)) / np.arange(1, d + 1), output_branches=output_branches,
    )


def _pnlss(rng, n=3, m=1, p=1, degrees=(2, 3)):
    ex = monomial_exponents(n + m, degrees)
    return PNLSSModel(
        A=np.diag(np.linspace(0.9, 0.3, n)) + 0.02 * rng.standard_normal((n, n)),
        B=0.1 * rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        E=0.05 * rng.standard_normal((n, len(ex))), F=0.05 * rng.standard_normal((p, len(ex))), exE=ex, exF=ex,
    )


def _trajectory(model, U):
    return np.hstack([model.simulate_states(U), U])


def _fd_jacobian(model, seg, h=1e-7):
    theta = model.theta
    J = np.empty((seg.Y.size, theta.size))
    for q in range(theta.size):
        d = np.zeros_like(theta)
        d[q] = h
        J[:, q] = (model.with_theta(theta + d).residual([seg]) - model.with_theta(theta - d).residual([seg])) / (2 * h)
    return J


@pytest.mark.parametrize("make, linear", [(_decoupled, False), (_decoupled, True), (_pnlss, False)])
def test_jacobian_is_exact_with_the_range_active(make, linear):
    rng = np.random.default_rng(3)
    model = make(rng)
    if linear:
        model.linear_extrapolation = True
    U = 0.1 * rng.standard_normal((300, 1))
    # A range between quantiles of the variables, so that they leave it
    # often (and no sample sits on an edge, where finite differences fail).
    v = model.bounded_variables(_trajectory(model, U))
    bounded = replace(model, bounds=np.quantile(v, [0.15, 0.85], axis=0).T)
    v = bounded.bounded_variables(_trajectory(bounded, U))
    outside = np.mean((v < bounded.bounds[:, 0]) | (v > bounded.bounds[:, 1]))
    assert outside > 0.05  # the test really exercises the continuation
    seg = Segment(U, np.zeros((290, 1)), 10)
    J = bounded.jacobian([seg])
    assert np.abs(J - _fd_jacobian(bounded, seg)).max() < 1e-5 * np.abs(J).max()


@pytest.mark.parametrize("make", [_decoupled, _pnlss])
def test_nothing_changes_inside_the_range(make):
    rng = np.random.default_rng(4)
    model = make(rng)
    U = 0.1 * rng.standard_normal((400, 1))
    bounded = model.with_trusted_range(_trajectory(model, U), margin=0.0)
    # To rounding: the range's extreme points are computed outside the kernel.
    Y = model.simulate(U)[0]
    np.testing.assert_allclose(bounded.simulate(U)[0], Y, rtol=0, atol=1e-13 * np.abs(Y).max())
    np.testing.assert_array_equal(bounded.without_bounds().bounds, model.bounds)


@pytest.mark.parametrize("make", [_decoupled, _pnlss])
def test_held_nonlinearity_keeps_a_stable_model_bounded(make):
    """A model that runs away at twice its training level stays bounded, with
    its state within what the held (bounded) nonlinearity and stable A allow."""
    rng = np.random.default_rng(5)
    model = make(rng)
    if make is _decoupled:
        model.G[:, -1] = 20.0  # a strong top-degree term: runs away on large inputs
    else:
        model.E[:, -4:] = 2.0
    U = 0.1 * rng.standard_normal((2000, 1))
    model.simulate(U)
    with pytest.raises(DivergenceError):
        model.simulate(4 * U)
    bounded = model.with_trusted_range(_trajectory(model, U), margin=0.1)
    Y, _ = bounded.simulate(4 * U)
    assert np.all(np.isfinite(Y))
    # |x| <= sum_k ||A^k|| (||B|| max|u| + max||nonlinear term||): a bound that
    # does not depend on how long the input lasts.
    gain = sum(np.linalg.norm(np.linalg.matrix_power(model.A, k), 2) for k in range(400))
    X = bounded.simulate_states(4 * U)
    assert gain < 100 and np.abs(X).max() < gain * 10
