"""A Bouc-Wen element's force along a prescribed motion (the locator's
hysteresis regressor): the exact per-sample solution agrees with a fine
explicit integration of the element's rate, and with the structure
integrator's own state along its simulated motion."""
import numpy as np
import pytest

from sklearn_pnlss.physics import BoucWen, Connection, Structure
from sklearn_pnlss.physics.hysteresis_path import bouc_wen_along


def _motion(t):
    return 1e-3 * np.sin(4 * np.pi * t) + 3e-4 * np.sin(14 * np.pi * t + 1.0)


@pytest.mark.parametrize("gamma, delta", [(0.5, 0.5), (0.5, -0.3), (0.8, -1.1)])
def test_the_force_along_a_motion_is_the_elements_rate_integrated(gamma, delta):
    """Two shapes of the benchmark family and the Jenkins-like joint: the
    steady-state force along one period agrees with an explicit integration
    of dz/dx over 100 times finer steps (two periods, the second kept) to
    1e-4 of its peak."""
    alpha, beta = 1e5, 1e4
    t = np.arange(4000) / 4000
    z = bouc_wen_along(_motion(t), alpha, beta, gamma, delta)
    fine = _motion(np.arange(800_000) / 400_000)
    steps = np.diff(fine, prepend=fine[-1])
    zz, out = 0.0, np.empty(fine.size)
    for i, dx in enumerate(steps):
        zz += dx * (alpha - beta * (gamma * np.sign(dx) * zz + delta * abs(zz)))
        out[i] = zz
    assert np.max(np.abs(out[400_000::100] - z)) < 1e-4 * np.max(np.abs(z))


def test_the_force_is_the_structures_along_its_own_motion():
    """A joint between two masses simulated by the structure's integrator:
    the force read along its simulated relative displacement is the
    integrator's internal state to 1e-3 of its peak in rms and 1 % at
    worst (the integrator's trapezoidal rule rounds the turns of the
    motion, where the exact solution switches branch within a step)."""
    M, K = np.diag([2.0, 1.0]), 4e4 * np.array([[2.0, -1.0], [-1.0, 1.0]])
    joint = BoucWen(2e4, 1e3, 0.5, 0.5, 1.0)
    s = Structure(M, 1e-4 * K + 0.5 * M, K, points=["a", "b"], connections=[Connection(joint, "a", "b")])
    rng = np.random.default_rng(0)
    spectrum = np.zeros(1025, complex)
    spectrum[5:400] = np.exp(2j * np.pi * rng.random(395))
    u = np.fft.irfft(spectrum)
    u *= 30.0 / u.std()
    sim = s.simulate_fine(np.repeat(u, 20)[:, None], fs=2000.0, inputs=["a"], periodic=True, warn=False)
    d = sim.y[:, 0] - sim.y[:, 1]
    z = bouc_wen_along(d, joint.alpha, joint.beta, joint.gamma, joint.delta)
    error = z - sim.z[:, 0]
    assert np.sqrt(np.mean(error**2)) < 1e-3 * np.max(np.abs(z))
    assert np.max(np.abs(error)) < 1e-2 * np.max(np.abs(z))


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="displacement must be one period"):
        bouc_wen_along(np.zeros((10, 2)), 1.0, 1.0, 0.5, 0.5)
    with pytest.raises(ValueError, match="alpha must be > 0 and beta >= 0"):
        bouc_wen_along(np.zeros(10), -1.0, 1.0, 0.5, 0.5)
