"""A linear structure of several degrees of freedom with nonlinear connections."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from sklearn_pnlss.physics import (
    BoucWen,
    Connection,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    DeadZoneSpring,
    Oscillator,
    StiffnessDrift,
    Structure,
    upsample_fft,
)

M = np.diag([2.0, 1.0])
K = 4e4 * np.array([[2.0, -1.0], [-1.0, 1.0]])
C = 2e-3 * K + 1.0 * M  # proportional: the modes decouple
POINTS = ["base", "tip"]


def _chain(connections=()):
    return Structure(M, C, K, points=POINTS, connections=connections)


def _two_tones(t):
    return 30 * np.sin(2 * np.pi * 12 * t) + 20 * np.sin(2 * np.pi * 31 * t)


def test_one_point_to_the_ground_is_the_oscillator():
    """A single degree of freedom with an element to the ground is the
    oscillator: the same Newmark scheme, converged to round-off."""
    osc = Oscillator(2.0, 10.0, 5e4, forces=(BoucWen(),))
    one = Structure(2.0, 10.0, 5e4, connections=[Connection(BoucWen(), "0")])
    t = np.arange(3000) / 15000.0
    u = 40 * np.sin(2 * np.pi * 30 * t) + 10 * np.sin(2 * np.pi * 5 * t)
    y = osc.simulate_fine(u, fs=15000.0, periodic=False).y
    sim = one.simulate_fine(u, fs=15000.0, inputs="0")
    assert np.max(np.abs(sim.y[:, 0] - y)) <= 1e-10 * np.max(np.abs(y))
    assert sim.n_newton_failures == 0


def test_a_chain_with_a_spring_between_its_masses_follows_the_continuous_dynamics():
    """Two masses, a cubic spring between them stiffening the link by a
    sixth or more at its peak: against a tight ODE solution, displacement
    and acceleration converge at Newmark's second order (halving the step
    quarters the error; the spring's sign flipped misses by 20 %)."""
    k3 = 3e10
    chain = _chain([Connection(CubicStiffness(k3), "tip", "base")])
    d = np.array([-1.0, 1.0])

    def rhs(tt, x):
        q, qd = x[:2], x[2:]
        force = np.array([_two_tones(tt), 0.0]) - C @ qd - K @ q - d * k3 * (d @ q) ** 3
        return np.r_[qd, np.linalg.solve(M, force)]

    errors = []
    for fs in (10000.0, 20000.0):
        t = np.arange(int(0.2 * fs)) / fs
        sim = chain.simulate_fine(_two_tones(t), fs=fs, inputs="base")
        ref = solve_ivp(rhs, (0, t[-1]), np.zeros(4), t_eval=t, rtol=1e-11, atol=1e-14, method="DOP853")
        q_ref = ref.y[:2].T
        acc_ref = np.array([rhs(tt, x)[2:] for tt, x in zip(t, ref.y.T)])
        assert 3 * k3 * np.max(np.abs(q_ref @ d)) ** 2 > 4e4 / 6  # the spring matters
        errors.append(np.max(np.abs(sim.y - q_ref)) / np.max(np.abs(q_ref)))
        assert np.max(np.abs(sim.ydd - acc_ref)) < 4 * errors[-1] * np.max(np.abs(acc_ref))
    assert errors[0] < 1e-4
    assert 3.6 < errors[0] / errors[1] < 4.4


def test_modes_and_matrices_give_the_same_records():
    """The chain given by its mass-normalised modes at its two points, and
    the same with the spring between them: the sensors read the same."""
    w2, phi = eigh(K, M)
    zeta = np.diag(phi.T @ C @ phi) / (2 * np.sqrt(w2))
    connection = [Connection(CubicStiffness(1e10), "tip", "base")]
    modal = Structure.from_modes(np.sqrt(w2) / (2 * np.pi), zeta, phi, points=POINTS, connections=connection)
    sensors = [("base", "acceleration"), ("tip", "displacement"), ("tip", "velocity")]
    t = np.arange(2000) / 10000.0
    u = _two_tones(t)
    a = _chain(connection).simulate_fine(u, fs=10000.0, inputs="base")
    b = modal.simulate_fine(u, fs=10000.0, inputs="base")
    ra, rb = _chain(connection).measure(a, sensors), modal.measure(b, sensors)
    assert np.all(np.max(np.abs(rb - ra), axis=0) <= 1e-9 * np.max(np.abs(ra), axis=0))


def test_connections_act_on_the_coupled_modes_only():
    """A mode that is not coupled (a residual mode of a modal fit) takes the
    inputs' forces but none of a connection's: a spring between the two
    points changes the records as if the mode had no shape at them, and the
    connection's response is the input response of that pair of forces on
    the coupled modes."""
    w2, phi = eigh(K, M)
    zeta = np.diag(phi.T @ C @ phi) / (2 * np.sqrt(w2))
    f = np.sqrt(w2) / (2 * np.pi)
    spring = [Connection(DeadZoneSpring(3e4, 0.0), "tip", "base")]
    sensors = [("base", "acceleration"), ("tip", "acceleration")]
    half = Structure.from_modes(f, zeta, phi, points=POINTS, coupled=[True, False])
    freqs = np.array([5.0, 20.0, 40.0])
    # the first mode's term alone, both sensors' accelerations
    s = 2j * np.pi * freqs[:, None]
    expected = phi[:, 0] * (phi[1, 0] - phi[0, 0]) * s**2 / (w2[0] + 2 * zeta[0] * np.sqrt(w2[0]) * s + s**2)
    np.testing.assert_allclose(half.connection_response(freqs, "tip", "base", sensors=sensors), expected,
                               rtol=1e-10)
    u = _two_tones(np.arange(2000) / 10000.0)
    plain = half.simulate_fine(u, fs=10000.0, inputs="base")
    joined = half.with_connections(spring).simulate_fine(u, fs=10000.0, inputs="base")
    np.testing.assert_allclose(joined.y[:, 1], plain.y[:, 1], rtol=0, atol=1e-12 * np.abs(plain.y).max())
    assert not np.allclose(joined.y[:, 0], plain.y[:, 0])


def test_a_periodic_linear_structure_answers_at_its_frequency_response():
    """The periodic steady state of the linear chain, shot from its period
    map (exact from the integrator's sensitivities, so one shot after the
    three plain periods settles it), reads at every excited line what the
    frequency response says, for displacement, velocity and acceleration."""
    n, fs, rate = 512, 500.0, 20
    lines = np.arange(3, 60, 4)
    rng = np.random.default_rng(0)
    spectrum = np.zeros(n // 2 + 1, complex)
    spectrum[lines] = np.exp(2j * np.pi * rng.random(lines.size))
    u = np.fft.irfft(spectrum, n) * n
    sim = _chain().simulate_fine(upsample_fft(u, rate, periodic=True), fs=fs * rate, inputs="tip", periodic=True,
                                 tol=1e-12)
    assert sim.n_periods <= 5
    sensors = [("base", "displacement"), ("tip", "velocity"), ("tip", "acceleration")]
    records = _chain().measure(sim, sensors)[::rate]
    measured = np.fft.rfft(records, axis=0)[lines] / np.fft.rfft(u)[lines, None]
    expected = _chain().frequency_response(lines * fs / n, inputs=["tip"], sensors=sensors)[:, :, 0]
    assert np.max(np.abs(measured / expected - 1)) < 2e-3


def test_a_periodic_nonlinear_steady_state_is_where_a_long_run_ends():
    chain = _chain([Connection(CubicStiffness(1e10), "tip", "base")])
    n, fs = 1000, 10000.0
    u = _two_tones(np.arange(n) / (n / 10) / 10)  # 1 period of both tones
    steady = chain.simulate_fine(u, fs=fs, inputs="base", periodic=True, tol=1e-11, max_periods=80)
    long = chain.simulate_fine(np.tile(u, 60), fs=fs, inputs="base")
    np.testing.assert_allclose(steady.y, long.y[-n:], rtol=0, atol=1e-7 * np.abs(steady.y).max())


def test_a_steep_friction_converges_at_every_step():
    """A friction smoothed over a velocity a hundredth of the motion's: a
    full Newton step overshoots the root far into the flat part of the law
    and back (4 500 of 10 000 steps failed, the steady state off by 0.3 %);
    halved where it leaves a larger residual, every step converges and the
    periodic steady state is where a long run ends."""
    chain = _chain([Connection(CoulombFriction(20.0, 1e-4), "tip", "base")])
    n, fs = 1000, 10000.0
    t = np.arange(n) / fs
    u = 30 * np.sin(2 * np.pi * 10 * t) + 20 * np.sin(2 * np.pi * 30 * t)
    steady = chain.simulate_fine(u, fs=fs, inputs="base", periodic=True, max_periods=80, warn=False)
    long = chain.simulate_fine(np.tile(u, 60), fs=fs, inputs="base")
    assert steady.n_newton_failures == 0 and long.n_newton_failures == 0
    np.testing.assert_allclose(steady.y, long.y[-n:], rtol=0, atol=1e-4 * np.abs(steady.y).max())


@pytest.mark.parametrize("make, match", [
    (lambda: Structure(np.eye(2), np.eye(3), np.eye(2)), "damping must be 2 x 2"),
    (lambda: Structure(-np.eye(2), np.eye(2), np.eye(2)), "positive definite"),
    (lambda: Structure(np.eye(2), np.eye(2), np.eye(2), points=["a", "a"]), "each of the 2"),
    (lambda: _chain([Connection(CubicStiffness(1.0), "wing")]), "'wing'"),
    (lambda: Connection(CubicStiffness(1.0), "tip", "tip"), "two different points"),
    (lambda: Connection(StiffnessDrift(1.0), "tip"), "time-invariant"),
    (lambda: Structure.from_modes([5.0, 12.0], [0.02], np.eye(2), points=POINTS), "damping_ratios"),
    (lambda: Structure.from_modes([5.0, 12.0], [0.02, 0.01], np.eye(3), points=POINTS), "mode_shapes"),
    (lambda: _chain().simulate_fine(np.ones((10, 2)), fs=100.0, inputs="tip"), "one column per input"),
    (lambda: _chain().simulate_fine(np.ones(10), fs=100.0, inputs="wing"), "'wing'"),
    (lambda: _chain().measure(None, [("tip", "jerk")]), "jerk"),
])
def test_bad_structures_and_arguments_say_what_to_fix(make, match):
    with pytest.raises((ValueError, TypeError), match=match):
        make()


SENSITIVITY_CONNECTIONS = {
    "cubic spring between the masses": [Connection(CubicStiffness(3e10), "tip", "base")],
    "hysteresis between them, friction to the ground": [
        Connection(BoucWen(2e4, 300.0, 0.8, -1.1, 1.0), "tip", "base"), Connection(CoulombFriction(2.0, 2e-3), "base")],
    "clearance to the ground, a second mode between them": [
        Connection(DeadZoneSpring(3e4, 1e-4, 1e-5), "tip"), Connection(CoupledMass(0.1, 2.0, 1e4), "base", "tip")],
}


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("name", sorted(SENSITIVITY_CONNECTIONS))
def test_sensitivities_are_the_derivatives_of_the_records(name, periodic):
    """The integrator's sensitivities of three sensors (an accelerometer, a
    displacement and a velocity sensor) by every connection parameter,
    against central differences of whole simulations; periodic: the
    steady state's own derivative through the period map."""
    connections = SENSITIVITY_CONNECTIONS[name]
    sensors = [("base", "acceleration"), ("tip", "displacement"), ("tip", "velocity")]
    fs = 5000.0
    t = np.arange(1000) / fs
    u = 30 * np.sin(2 * np.pi * 10 * t) + 20 * np.sin(2 * np.pi * 35 * t)

    def records(p):
        moved = _chain(connections)
        moved._packed[2][:] = p
        sim = moved.simulate_fine(u, fs=fs, inputs="base", periodic=periodic, tol=1e-12, max_periods=300)
        return moved.measure(sim, sensors)

    chain = _chain(connections)
    steady = chain.simulate_fine(u, fs=fs, inputs="base", periodic=True, tol=1e-12).final_state if periodic else None
    y, dy = chain.sensitivity(u, fs=fs, inputs="base", sensors=sensors, periodic=periodic, steady_state=steady)
    p0 = chain.parameter_vector
    np.testing.assert_allclose(y, records(p0), rtol=0, atol=1e-10 * np.abs(y).max())
    for i in range(p0.size):
        if isinstance(connections[0].element, BoucWen) and i == 4:
            continue  # the exponent nu: |z|^(nu - 1) at z = 0 has no difference across nu = 1
        step = 1e-6 * abs(p0[i])
        up, down = p0.copy(), p0.copy()
        up[i] += step
        down[i] -= step
        fd = (records(up) - records(down)) / (2 * step)
        assert np.linalg.norm(dy[:, :, i] - fd) <= 1e-3 * np.linalg.norm(fd), (name, i)
