"""Records that do not start from rest: the initial state read off the first
measured outputs (``predict(X, y_init=...)``, the field's state-initialisation
window), and an operating point (``BLAEstimator(offsets=True)``)."""
import numpy as np
import pytest
from scipy.signal import lfilter

from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.metrics import rms_error, signal_scorer
from sklearn_pnlss.statespace.initial_state import estimate_initial_state
from sklearn_pnlss.statespace.model_base import Segment
from sklearn_pnlss.statespace.pnlss import PNLSSModel

N = 4096


def _record(offset_u=0.0, offset_y=0.0, seed=0):
    """A lightly damped second-order system driven by filtered noise around an operating
    point, recorded over 3 N samples: the first N to fit, the middle cut
    off, the last N (started mid-run) to test."""
    rng = np.random.default_rng(seed)
    u = lfilter([1.0], [1.0, -0.5], rng.standard_normal(3 * N))
    y = lfilter([0.0, 0.03, 0.02], [1.0, -1.9, 0.9604], u)  # poles at radius 0.98: a 50-sample decay
    return (offset_u + u[:N], offset_y + y[:N]), (offset_u + u[2 * N:], offset_y + y[2 * N:])


def _started_record():
    """A two-state nonlinear model (x1^2, x2 u, x1^3) and 200 samples of
    its output from the state ``x_true``, not from rest."""
    ex = np.array([[2, 0, 0], [0, 1, 1], [3, 0, 0]])
    model = PNLSSModel(A=np.array([[0.5, 0.3], [-0.3, 0.6]]), B=np.array([[1.0], [0.5]]),
                       C=np.array([[1.0, 0.5]]), D=np.zeros((1, 1)),
                       E=np.array([[0.05, 0.02, -0.01], [0.0, 0.03, 0.0]]), F=np.zeros((1, 0)),
                       exE=ex, exF=np.zeros((0, 3), dtype=int))
    U = np.random.default_rng(1).standard_normal((200, 1))
    x_true = np.array([0.7, -0.4])
    return model, U, x_true, model.simulate(U, x_true)[0]


def test_a_state_is_recovered_from_a_short_window_of_a_nonlinear_model():
    model, U, x_true, Y = _started_record()
    x0 = estimate_initial_state(model, U, Y[:20])
    assert np.allclose(x0, x_true, atol=1e-7)


def test_the_trusted_range_follows_the_trajectory_the_cost_simulates():
    # A record that does not start from rest is simulated by the cost from
    # the state its first samples show; the trusted range of the fitted
    # nonlinearity (and the step basis) must be read along that trajectory,
    # not one from rest, which a model can diverge on that the cost never
    # saw diverge (EMPS's increments with a spline branch did).
    model, U, x_true, Y = _started_record()
    seg = Segment(U, Y, 0, init_window=20)
    path = model.segments_trajectory([seg])
    assert np.allclose(path[0, :2], x_true, atol=1e-7) and np.array_equal(path[:, 2:], U)
    assert np.allclose(path[:, :2], model.simulate_states(U, x_true), atol=1e-6)


def test_a_record_cut_from_a_run_is_simulated_from_its_state():
    (u, y), (u_test, y_test) = _record()
    model = BLAEstimator(2, offsets=False).fit(u, y)
    from_rest = rms_error(y_test, model.predict(u_test), skip=50)
    initialised = rms_error(y_test, model.predict(u_test, y_init=y_test[:50]), skip=50)
    # From rest the first few dozen samples carry a transient the system
    # never showed; the state read off 50 samples removes it.
    assert initialised < 0.2 * from_rest
    assert initialised < 0.01 * np.std(y_test)


def test_offsets_model_an_operating_point():
    (u, y), (u_test, y_test) = _record(offset_u=3.0, offset_y=5.0)
    through_origin = BLAEstimator(2, offsets=False).fit(u, y)
    with pytest.warns(UserWarning, match="offsets=True"):
        BLAEstimator(2).fit(u, y)
    operating = BLAEstimator(2, offsets=True).fit(u, y)
    assert operating.input_offset_ == pytest.approx([np.mean(u)])
    assert operating.output_offset_ == pytest.approx([np.mean(y)])
    err_origin = rms_error(y_test, through_origin.predict(u_test, y_init=y_test[:50]), skip=50)
    err_operating = rms_error(y_test, operating.predict(u_test, y_init=y_test[:50]), skip=50)
    # A model through the origin cannot hold both the 5 V level and the
    # gain of the deviations around it.
    assert err_operating < 0.01 * np.std(y_test) < err_origin


def test_a_nonlinear_model_keeps_its_linear_start_s_operating_point():
    (u, y), (u_test, y_test) = _record(offset_u=3.0, offset_y=5.0)
    y, y_test = y + 0.05 * (y - 5.0) ** 2, y_test + 0.05 * (y_test - 5.0) ** 2
    model = PNLSSRegressor(2, degrees=(2,), variables="states", equations="output", max_iter=20,
                           linear_model=BLAEstimator(2, offsets=True)).fit(u, y)
    assert model.model_.output_offset == pytest.approx([np.mean(y)])
    assert model.exponents_F_[0].tolist() == [0, 0, 0]  # the constant term
    linear = BLAEstimator(2, offsets=True).fit(u, y)
    err_linear = rms_error(y_test, linear.predict(u_test, y_init=y_test[:50]), skip=50)
    err = rms_error(y_test, model.predict(u_test, y_init=y_test[:50]), skip=50)
    assert err < 0.05 * err_linear


def test_the_scorer_starts_held_out_signals_from_their_window():
    (u, y), (u_test, y_test) = _record()
    model = BLAEstimator(2).fit(u, y)
    plain = signal_scorer("neg_root_mean_squared_error")(model, u_test, y_test)
    windowed = signal_scorer("neg_root_mean_squared_error", init_window=50)
    assert repr(windowed) == "signal_scorer('neg_root_mean_squared_error', init_window=50)"
    assert windowed(model, u_test, y_test) == pytest.approx(
        -rms_error(y_test, model.predict(u_test, y_init=y_test[:50]), skip=50))
    assert windowed(model, u_test, y_test) > plain


@pytest.mark.parametrize("y_init, match", [
    (np.zeros((50, 2)), "1 output"),
    (np.zeros((N + 1, 1)), "only 4096"),
    ([np.zeros((50, 1))] * 2, "one window"),
])
def test_bad_windows_name_the_fix(y_init, match):
    (u, y), _ = _record()
    model = BLAEstimator(2).fit(u, y)
    with pytest.raises(ValueError, match=match):
        model.predict(u, y_init=y_init)
