"""modes_by_level: the modes of a linear model of each excitation level,
of the measurement and of a fitted model's simulation."""
import numpy as np
import pytest
from scipy.signal import cont2discrete, dlsim

from sklearn_pnlss.datasets import simulate_bouc_wen
from sklearn_pnlss.level_modes import _paired, modes_by_level
from sklearn_pnlss.signals import multisine

FS, PERIOD = 750.0, 2048


def _two_modes(f1, z1, f2, z2):
    """A discrete-time system of two modes (Hz, damping ratio), one input,
    one output (an acceleration-like feedthrough)."""
    blocks = []
    for f, z in ((f1, z1), (f2, z2)):
        w = 2 * np.pi * f
        blocks.append(np.array([[0.0, 1.0], [-w * w, -2 * z * w]]))
    A = np.block([[blocks[0], np.zeros((2, 2))], [np.zeros((2, 2)), blocks[1]]])
    B = np.array([[0.0], [1.0], [0.0], [1.0]])
    C = np.array([[1000.0, 1.0, 500.0, 1.0]])
    Ad, Bd, Cd, Dd, _ = cont2discrete((A, B, C, np.zeros((1, 1))), 1 / FS, method="zoh")
    return Ad, Bd, Cd, Dd


def _steady_response(system, u):
    """Output of ``system`` to the periodic input ``u`` (one period), in
    steady state, two periods."""
    A, B, C, D = system
    _, y, _ = dlsim((A, B, C, D, 1 / FS), np.tile(u, 6))  # the slowest mode has decayed after four periods
    return y[-2 * u.size:]


class _LinearModel:
    """A 'fitted model' whose simulation is another linear system's."""

    def __init__(self, system):
        self.system = system

    def predict(self, X):
        return _steady_response(self.system, np.asarray(X)[:PERIOD, 0])


@pytest.fixture(scope="module")
def excitation():
    u, _ = multisine(PERIOD, fs=FS, f_band=(5.0, 150.0), random_state=0)
    return u[0, :, 0]


def test_a_linear_structure_gives_its_own_modes_at_every_level_and_the_model_its_own(excitation):
    truth = _two_modes(20.0, 0.02, 60.0, 0.01)
    shifted = _two_modes(21.0, 0.03, 59.0, 0.01)
    X = [np.tile(a * excitation, 2)[:, None] for a in (1.0, 3.0)]
    y = [_steady_response(truth, x[:PERIOD, 0]) for x in X]
    modes = modes_by_level(X, y, _LinearModel(shifted), n_states=4, period=PERIOD, fs=FS)
    np.testing.assert_allclose(modes.input_rms, [1.0, 3.0], rtol=1e-6)
    np.testing.assert_allclose(modes.frequencies, [[20.0, 60.0]] * 2, rtol=1e-4)
    np.testing.assert_allclose(modes.damping, [[0.02, 0.01]] * 2, rtol=1e-3)
    np.testing.assert_allclose(modes.model_frequencies, [[21.0, 59.0]] * 2, rtol=1e-4)
    np.testing.assert_allclose(modes.model_damping, [[0.03, 0.01]] * 2, rtol=1e-3)
    table = str(modes)
    assert "level 2 (input rms 3)" in table and "model  21.000" in table
    assert modes.to_dict()["model_frequencies"][0][0] == pytest.approx(21.0, rel=1e-4)


def test_the_bouc_wen_oscillator_damps_more_as_the_force_grows(excitation):
    X = [np.tile(rms * excitation, 2)[:, None] for rms in (1.0, 20.0, 50.0, 100.0)]
    y = [np.tile(simulate_bouc_wen(x[:PERIOD, 0], periodic=True), 2)[:, None] for x in X]
    modes = modes_by_level(X, y, n_states=2, period=PERIOD, fs=FS)
    damping = 100 * modes.damping[:, 0]
    # the hysteresis loop widens with the amplitude: 1.6 % at 1 N, 13 % at 100 N
    assert np.all(np.diff(damping) > 2.0) and damping[0] < 2.0 and damping[-1] > 12.0
    assert modes.model_frequencies is None and modes.to_dict()["model_damping"] is None


def test_a_mode_without_a_partner_is_nan():
    freq, damp = _paired(np.array([59.0]), np.array([0.01]), np.array([20.0, 60.0]))
    np.testing.assert_array_equal(freq, [np.nan, 59.0])
    np.testing.assert_array_equal(damp, [np.nan, 0.01])
    # a model that lacks the 6.6 Hz mode and has one far above: the others
    # keep their partners (the F-16's modes, level 1)
    ref = np.array([3.457, 5.195, 6.618, 7.320, 9.167])
    model = np.array([3.450, 5.192, 7.320, 9.165, 18.852])
    freq, _ = _paired(model, np.arange(5.0), ref)
    np.testing.assert_array_equal(freq, [3.450, 5.192, np.nan, 7.320, 9.165])


def test_levels_must_pair_up():
    with pytest.raises(ValueError, match="X_levels and y_levels"):
        modes_by_level([np.zeros((4096, 1))], [], n_states=2, period=PERIOD)
