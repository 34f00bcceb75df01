"""statespace/linear.py: simulation, frequency response, exact periodic
steady state, stability and modal parameters of known systems."""
import numpy as np
import pytest
from scipy.signal import dlsim, freqz

from sklearn_pnlss.statespace.linear import (
    frequency_response,
    is_stable,
    modal_parameters,
    periodic_initial_state,
    resolvent_products,
    simulate_linear,
    simulate_linear_signal,
    stabilize,
)


def _resonator(f0=5.0, zeta=0.02, fs=100.0):
    """A discrete pole pair at f0 Hz with damping zeta, as (A, B, C, D)."""
    wn = 2 * np.pi * f0
    z = np.exp((-zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)) / fs)
    A = np.array([[2 * z.real, -abs(z) ** 2], [1.0, 0.0]])
    return A, np.array([[1.0], [0.0]]), np.array([[0.3, 0.1]]), np.array([[0.05]])


def test_simulation_matches_scipy():
    A, B, C, D = _resonator()
    U = np.random.default_rng(0).standard_normal((500, 1))
    Y, x_end = simulate_linear(A, B, C, D, U)
    _, y_ref, x_ref = dlsim((A, B, C, D, 1.0), U[:, 0])
    np.testing.assert_allclose(Y[:, 0], y_ref[:, 0], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(x_end, A @ x_ref[-1] + B @ U[-1], rtol=1e-10)


def test_frequency_response_matches_the_transfer_function():
    A, B, C, D = _resonator()
    w = np.linspace(0.01, np.pi, 50)
    G = frequency_response(A, B, C, D, np.exp(1j * w))[:, 0, 0]
    # Transfer function of the companion form: (0.3 z + 0.1) / (z^2 - a1 z + a2) + 0.05
    num = np.polyadd(np.polymul([0.05], [1, -A[0, 0], -A[0, 1]]), [0.0, 0.3, 0.1])
    _, H = freqz(num, [1, -A[0, 0], -A[0, 1]], worN=w)
    np.testing.assert_allclose(G, H, rtol=1e-10)


def test_periodic_steady_state_is_exact():
    """From the periodic initial state, one period ends where it started,
    and the output equals that of 60 periods simulated from rest."""
    A, B, C, D = _resonator(zeta=0.01)
    P = 256
    U = np.random.default_rng(1).standard_normal((P, 1))
    x0 = periodic_initial_state(A, B, C, D, U)
    _, x_end = simulate_linear(A, B, C, D, U, x0)
    np.testing.assert_allclose(x_end, x0, rtol=1e-10, atol=1e-12)
    long_run = simulate_linear(A, B, C, D, np.tile(U, (60, 1)))[0][-P:]
    np.testing.assert_allclose(simulate_linear_signal(A, B, C, D, np.tile(U, (2, 1)), periodic_with=P)[P:],
                               long_run, rtol=1e-8, atol=1e-10)


def test_modal_parameters_of_a_known_pole():
    A = _resonator(f0=5.0, zeta=0.02)[0]
    f, d = modal_parameters(A, fs=100.0)
    assert f[0] == pytest.approx(5.0, rel=1e-10)
    assert d[0] == pytest.approx(0.02, rel=1e-10)


def test_stabilize_reflects_unstable_poles_and_keeps_stable_ones():
    # A pole pair 1.25 exp(+-0.3j) (a real rotation-scaling block) and 0.5,
    # in a random basis.
    r, w = 1.25, 0.3
    block = np.array([[r * np.cos(w), -r * np.sin(w), 0.0], [r * np.sin(w), r * np.cos(w), 0.0], [0.0, 0.0, 0.5]])
    T = np.random.default_rng(2).standard_normal((3, 3))
    A = T @ block @ np.linalg.inv(T)
    assert not is_stable(A)
    stable = stabilize(A)
    assert is_stable(stable)
    poles = np.linalg.eigvals(stable)
    np.testing.assert_allclose(np.sort(np.abs(poles)), [0.5, 0.8, 0.8], rtol=1e-10)  # 1 / 1.25
    np.testing.assert_allclose(np.sort(np.abs(np.angle(poles))), [0.0, 0.3, 0.3], atol=1e-10)
    np.testing.assert_array_equal(stabilize(stable), stable)
    assert not is_stable(np.diag([0.95, 0.2]), margin=0.1) and is_stable(np.diag([0.85, 0.2]), margin=0.1)


@pytest.mark.parametrize("A", [
    np.diag([0.9, 0.5, -0.3]) + 0.05 * np.random.default_rng(3).standard_normal((3, 3)),  # diagonalisable
    np.array([[0.8, 1.0, 0.0], [0.0, 0.8, 1.0], [0.0, 0.0, 0.8]]),  # a Jordan block: solved line by line
], ids=["eigendecomposition", "defective"])
def test_resolvent_products_equal_the_solves(A):
    rng = np.random.default_rng(4)
    B, C = rng.standard_normal((3, 2)), rng.standard_normal((4, 3))
    z = np.exp(1j * np.linspace(0.01, 3.0, 50))
    PB, CP = resolvent_products(A, z, B=B, C=C)
    R = np.linalg.inv(z[:, None, None] * np.eye(3) - A)
    np.testing.assert_allclose(PB, R @ B, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(CP, C @ R, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(frequency_response(A, B, C, np.zeros((4, 2)), z), C @ R @ B, rtol=1e-10, atol=1e-12)
    assert resolvent_products(A, z)[0] is None
