"""ScaledModel (statespace/scaled.py) and the models' ``rescaled``: a model
fitted on normalised signals simulates, and exports itself, in the user's
units exactly."""
import numpy as np
import pytest

from sklearn_pnlss.statespace.decoupled import DecoupledModel
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel
from sklearn_pnlss.statespace.scaled import ScaledModel, unit_rms_scales

N_STATES, N_INPUTS, N_OUTPUTS = 3, 2, 2


def _pnlss(rng, bounds=None):
    k = N_STATES + N_INPUTS
    exE = monomial_exponents(k, (2, 3))
    exF = monomial_exponents(k, (2,))
    return PNLSSModel(
        A=np.diag([0.8, 0.5, -0.3]) + 0.05 * rng.standard_normal((N_STATES, N_STATES)),
        B=rng.standard_normal((N_STATES, N_INPUTS)), C=rng.standard_normal((N_OUTPUTS, N_STATES)),
        D=rng.standard_normal((N_OUTPUTS, N_INPUTS)), E=0.005 * rng.standard_normal((N_STATES, len(exE))),
        F=0.02 * rng.standard_normal((N_OUTPUTS, len(exF))), exE=exE, exF=exF, bounds=bounds,
    )


def _decoupled(rng, bounds=None, linear=False):
    r, d = 2, 5
    return DecoupledModel(
        A=np.diag([0.8, 0.5, -0.3]), B=rng.standard_normal((N_STATES, N_INPUTS)),
        C=rng.standard_normal((N_OUTPUTS, N_STATES)), D=rng.standard_normal((N_OUTPUTS, N_INPUTS)),
        Wx=0.3 * rng.standard_normal((N_STATES, r)), Wy=0.3 * rng.standard_normal((N_OUTPUTS, r)),
        V=rng.standard_normal((N_STATES + N_INPUTS, r)), G=0.1 * rng.standard_normal((r, d)),
        output_branches=True, bounds=bounds, linear_extrapolation=linear,
    )


def _scales():
    # Scales far from one and unequal per channel: a transposed or inverted
    # scale shows at once.
    return np.array([3.0, 0.02]), np.array([50.0, 1e-3]), np.array([7.0, 0.1, 2e3])


@pytest.mark.parametrize("make", [
    lambda rng: _pnlss(rng),
    lambda rng: _pnlss(rng, bounds=[[-1, 1], [-0.5, 0.8], [-2, 0.3], [-np.inf, np.inf], [-np.inf, np.inf]]),
    lambda rng: _decoupled(rng),
    lambda rng: _decoupled(rng, bounds=[[-0.4, 0.5], [-0.3, 0.2]]),
    lambda rng: _decoupled(rng, bounds=[[-0.4, 0.5], [-0.3, 0.2]], linear=True),
], ids=["pnlss", "pnlss-held", "decoupled", "decoupled-held", "decoupled-tangent"])
def test_model_in_user_units_simulates_the_scaled_signals(make):
    rng = np.random.default_rng(0)
    u_scale, y_scale, x_scale = _scales()
    scaled = ScaledModel(make(rng), u_scale, y_scale, x_scale)
    U = 0.6 * rng.standard_normal((300, N_INPUTS)) * u_scale
    Y = scaled.simulate(U)
    # By hand: normalise, simulate, scale back.
    np.testing.assert_allclose(Y, scaled.normalised.simulate(U / u_scale)[0] * y_scale, rtol=1e-14)
    user = scaled.in_user_units()
    assert type(user) is type(scaled.normalised)
    np.testing.assert_allclose(user.simulate(U)[0], Y, rtol=1e-9, atol=1e-12 * np.abs(Y).max())
    # The states along the simulation, in user units.
    s = scaled.states_inputs(U)
    np.testing.assert_allclose(s[:, N_STATES:], U, rtol=1e-15)
    np.testing.assert_allclose(s[:, :N_STATES], user.simulate_states(U), rtol=1e-9, atol=1e-12 * np.abs(s).max())
    # The trusted range moves with its variables: the same excursion.
    assert scaled.range_excursion(3 * U) == pytest.approx(user.range_excursion(3 * U), rel=1e-9, abs=1e-12)


def test_rescaled_pnlss_coefficients_by_hand():
    """x(t+1) = 0.5 x + u + 0.1 x^2 u in normalised units, x = 4 x_n,
    u = 2 u_n, y = 10 y_n: the user-unit coefficient of x^2 u is
    0.1 * 4 / (4^2 * 2) = 0.0125, B = 4 / 2 = 2, C = 10 / 4 = 2.5."""
    ex = np.array([[2, 1]])
    unit = PNLSSModel(A=np.array([[0.5]]), B=np.array([[1.0]]), C=np.array([[1.0]]), D=np.array([[0.0]]),
                      E=np.array([[0.1]]), F=np.zeros((1, 0)), exE=ex, exF=np.zeros((0, 2), dtype=int),
                      bounds=[[-1.0, 1.5], [-np.inf, np.inf]])
    user = unit.rescaled(np.array([4.0]), np.array([2.0]), np.array([10.0]))
    assert (user.A[0, 0], user.B[0, 0], user.C[0, 0]) == (0.5, 2.0, 2.5)
    assert user.E[0, 0] == pytest.approx(0.0125, rel=1e-15)
    np.testing.assert_array_equal(user.bounds, [[-4.0, 6.0], [-np.inf, np.inf]])


def test_unit_rms_scales():
    signals = [np.array([[3.0, 0.0], [-3.0, 0.0]]), np.array([[3.0, 0.0]])]
    np.testing.assert_array_equal(unit_rms_scales(signals), [3.0, 1.0])  # silent channel: 1


def test_every_estimator_exposes_its_model(small_pipeline, small_data):
    """BLA, PNLSS and decoupled: ``model_`` simulates what ``predict`` gives,
    and its user-unit form holds the exported matrices."""
    period = small_pipeline[0].period
    for est in small_pipeline:
        model = est.model_
        user = model.in_user_units()
        for name in "ABCD":
            np.testing.assert_allclose(getattr(user, name), getattr(est, name + "_"), rtol=1e-12, atol=1e-14)
        X = small_data.X_val
        y_pred = est.predict(X)
        for U, Y in zip(X, y_pred):
            # BLA predicts with the exact linear steady state; the model's
            # steady state is iterated to 1e-10.
            np.testing.assert_allclose(model.simulate(U, period), Y, rtol=1e-8, atol=1e-9 * np.abs(Y).max())
