"""A located connection's fit by simulation (gap.connections.refine): the
steps of a Jacobian, simulated side by side from the point's own steady
states, give what each gives simulated alone; a step that runs away gets
the penalty without costing the others theirs."""
import numpy as np

from sklearn_pnlss.gap.connections.locator import band_and_weights
from sklearn_pnlss.gap.connections.refine import BandError
from sklearn_pnlss.physics import Connection, DeadZoneSpring, Structure

from test_connection_locator import C, K, M, POINTS, SENSORS, _locator, _records


def _band_error():
    X, Y = _records(DeadZoneSpring(3e4, 1e-3), (20.0, 60.0))
    spectra = _locator()._spectra(X, Y)
    lines, weights = band_and_weights(spectra, None)
    return BandError(spectra, lines, weights, ["base"], SENSORS, oversampling=5)


def _with_backlash(kb):
    return Structure(M, C, K, points=POINTS).with_connections([Connection(DeadZoneSpring(kb, 1e-3), "middle", "tip")])


def test_a_jacobians_steps_side_by_side_match_each_simulated_alone():
    error = _band_error()
    error.simulate(_with_backlash(3e4))  # the point whose steps these are
    steps = [_with_backlash(3e4 * (1 + 1e-4)), _with_backlash(4.5e4)]
    side_by_side = error.residuals_around(steps)
    size = np.sqrt(np.mean(np.abs(error.measured) ** 2))
    for structure, residuals in zip(steps, side_by_side):
        error.forget_starts()
        alone = error.residuals(structure)
        assert np.max(np.abs(residuals - alone)) < 1e-7 * size
    # the small step moves the residual by about its own size, not by
    # the steady-state search's tolerance
    step = side_by_side[0] - error.residuals(_with_backlash(3e4))
    assert 1e-6 * size < np.max(np.abs(step)) < 1e-2 * size
    assert error.n_simulations == 1 + 2 + 2 + 1


def test_a_step_that_runs_away_gets_the_penalty_and_the_others_their_residuals():
    error = _band_error()
    error.simulate(_with_backlash(3e4))
    unstable = Structure(M, C, K, points=POINTS).with_connections([], springs=[("middle", "tip", -3e5, 0.0)])
    runaway, fine = error.residuals_around([unstable, _with_backlash(3.3e4)])
    np.testing.assert_array_equal(runaway, error.penalty())
    error.forget_starts()
    np.testing.assert_allclose(fine, error.residuals(_with_backlash(3.3e4)), atol=1e-6 * np.abs(fine).max())
    assert np.abs(fine).max() < 1e-2 * error.penalty()[0]
