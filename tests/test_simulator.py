import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp
from scipy.io import loadmat
from scipy.signal import lfilter
from sklearn.exceptions import ConvergenceWarning

from sklearn_pnlss.datasets import bouc_wen_oscillator, simulate_bouc_wen
from sklearn_pnlss.physics import (
    BoucWen,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    CustomForce,
    DeadZoneSpring,
    Oscillator,
    QuadraticDamping,
    QuadraticStiffness,
    SeriesDamper,
    StiffnessDrift,
    decimate_fir,
    fir_decimation_filter,
    upsample_fft,
)
from sklearn_pnlss.physics.resampling import decimate_columns
from sklearn_pnlss.signals import bouc_wen_sweep, linear_chirp

M, C, K = 2.0, 10.0, 5e4


def _rel_rms(a, b):
    return np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2))


def _few_line_signal(n, lines, seed=0):
    rng = np.random.RandomState(seed)
    spec = np.zeros(n // 2 + 1, complex)
    spec[lines] = np.exp(2j * np.pi * rng.rand(len(lines)))
    x = np.fft.irfft(spec, n)
    return 10 * x / x.std()


def _zero_phase_gain(b, f, rate):
    j = np.arange(b.size) - (b.size - 1) / 2
    return np.cos(2 * np.pi * np.outer(f, j) / rate) @ b


# ---------------------------------------------------------------- decimation
def _matlab_decimate_reference(x, r):
    """Direct transcription of the documented MATLAB 'fir' procedure."""
    b = fir_decimation_filter(r)
    n = x.size
    x1 = np.concatenate([[np.nan], x])  # 1-based view
    front = 2 * x1[1] - x1[32:1:-1]
    back = 2 * x1[n] - x1[n - 1:n - 63:-1]
    y = lfilter(b, 1.0, np.concatenate([front, x, back]))
    y = y[31:]  # drop the front extension
    picks = np.arange(16, 16 + r * int(np.ceil(n / r)), r)  # 1-based
    return y[picks - 1]


@pytest.mark.parametrize("r", [2, 5, 20])
@pytest.mark.parametrize("n", [400, 401, 1003])
def test_decimate_matches_matlab_procedure(r, n):
    x = np.random.RandomState(n + r).randn(n).cumsum()
    got = decimate_fir(x, r)
    assert got.shape == (int(np.ceil(n / r)),)
    np.testing.assert_allclose(got, _matlab_decimate_reference(x, r), rtol=0, atol=1e-12)


def test_decimate_keeps_linear_trends_exactly():
    # point reflection continues a straight line; the filter is symmetric
    x = 0.3 + 0.01 * np.arange(2000)
    np.testing.assert_allclose(decimate_fir(x, (2, 2, 5)), x[::20], atol=1e-12)


def test_decimate_periodic_is_circular_and_matches_interior():
    n, r = 600, 5
    x = _few_line_signal(n, [3, 17, 40])
    per = decimate_fir(x, r, periodic=True)
    long = decimate_fir(np.tile(x, 5), r)
    np.testing.assert_allclose(per, long[2 * n // r: 3 * n // r], atol=1e-12)
    # a pure tone is scaled by the filter's zero-phase gain only
    tone = np.cos(2 * np.pi * 17 * np.arange(n) / n)
    gain = _zero_phase_gain(fir_decimation_filter(r), [17.0], n)[0]
    np.testing.assert_allclose(decimate_fir(tone, r, periodic=True), gain * tone[::r],
                               atol=1e-12)


@pytest.mark.parametrize("periodic", [False, True])
def test_decimating_columns_decimates_each_record(periodic):
    x = np.random.RandomState(0).standard_normal((2000, 3))
    out = decimate_columns(x, (2, 5), periodic=periodic)
    for j in range(3):
        np.testing.assert_allclose(out[:, j], decimate_fir(x[:, j], (2, 5), periodic=periodic), rtol=0, atol=1e-14)


def test_decimate_errors():
    with pytest.raises(ValueError, match="divisible"):
        decimate_fir(np.ones(101), 2, periodic=True)
    with pytest.raises(ValueError, match="more than 62"):
        decimate_fir(np.ones(50), 2)
    with pytest.raises(ValueError, match="1-D"):
        decimate_fir(np.ones((100, 2)), 2)
    with pytest.raises(ValueError, match="NaN"):
        decimate_fir(np.r_[np.ones(100), np.nan], 2)
    with pytest.raises(ValueError, match="positive integer"):
        decimate_fir(np.ones(100), (2, 0))


# ---------------------------------------------------------------- upsampling
def test_upsample_periodic_is_exact():
    n = 256
    x = _few_line_signal(n, [1, 30, 127, 128])
    fine = upsample_fft(x, 8, periodic=True)
    spec = np.fft.rfft(x)
    t = np.arange(n * 8) / (n * 8)
    ref = np.full(t.size, spec[0].real / n)
    for k in range(1, n // 2 + 1):
        w = 1.0 if k == n // 2 else 2.0
        ref += w * np.abs(spec[k]) / n * np.cos(2 * np.pi * k * t * n / n + np.angle(spec[k]))
    np.testing.assert_allclose(fine, ref, atol=1e-12)
    np.testing.assert_allclose(fine[::8], x, atol=1e-12)


def test_upsample_reflected_sweep_is_accurate():
    u = bouc_wen_sweep()
    fine = upsample_fft(u, 20, periodic=False)
    exact = bouc_wen_sweep(oversampling=20)
    np.testing.assert_allclose(fine[::20], u, atol=1e-9)
    # away from the last samples (where it extrapolates) the error is ~1e-7
    err = np.abs(fine - exact)[: -20 * 20]
    assert np.sqrt(np.mean(err**2)) / 40 < 3e-7


# ---------------------------------------------------------------- integrator
def _linear_periodic_frf(osc, lines, n=1024, fs=750.0, oversampling=20,
                         decimation=(2, 2, 5)):
    u = _few_line_signal(n, lines)
    y = osc.simulate(u, fs=fs, periodic=True, oversampling=oversampling,
                     decimation=decimation)
    return np.fft.rfft(y)[lines] / np.fft.rfft(u)[lines]


def _tustin_frf(f, h, m=M, c=C, k=K):
    s = 2.0 / h * 1j * np.tan(np.pi * f * h)  # Newmark (1/2, 1/4) == bilinear map
    return 1.0 / (m * s**2 + c * s + k)


def test_linear_oscillator_matches_exact_frequency_response():
    fs, n, lines = 750.0, 1024, np.array([20, 48, 49, 50, 100, 200])
    f = lines * fs / n
    osc = Oscillator(M, C, K)
    frf = _linear_periodic_frf(osc, lines)
    gain = np.ones(f.size)
    rate = 20 * fs
    for r in (2, 2, 5):
        gain *= _zero_phase_gain(fir_decimation_filter(r), f, rate)
        rate /= r
    expected = _tustin_frf(f, 1 / (20 * fs)) * gain
    np.testing.assert_allclose(frf, expected, rtol=1e-8)
    # and the discretisation stays close to the continuous system
    cont = 1.0 / (M * (2j * np.pi * f) ** 2 + C * 2j * np.pi * f + K)
    assert np.max(np.abs(frf / gain - cont) / np.abs(cont)) < 3e-3


def test_bouc_wen_without_hysteresis_is_a_linear_spring():
    # beta = 0: z' = alpha y', so z = alpha y exactly under both trapezoid rules
    lines = np.array([20, 48, 49, 50, 100, 200])
    with_bw = Oscillator(M, C, K, forces=(BoucWen(beta=0.0),))
    linear = Oscillator(M, C, K + 5e4)
    np.testing.assert_allclose(_linear_periodic_frf(with_bw, lines),
                               _linear_periodic_frf(linear, lines), rtol=1e-10)


def _continuous_reference(forces_rhs, n_z, t_end, fs_out, amp, f0, rate):
    def rhs(t, s):
        y, yd = s[0], s[1]
        z = s[2:]
        u = linear_chirp(t, f_start=f0, rate=rate, amplitude=amp)
        f, zd = forces_rhs(y, yd, z)
        return np.r_[yd, (u - C * yd - K * y - f) / M, zd]

    t = np.arange(int(t_end * fs_out)) / fs_out
    sol = solve_ivp(rhs, (0, t[-1]), np.zeros(2 + n_z), t_eval=t, rtol=1e-10,
                    atol=1e-13, method="DOP853", max_step=1e-3)
    return sol.y[0]


@njit
def _cubic_spring_and_damper(p, y, yd):
    return p[0] * y**3 + p[1] * yd**3, 3.0 * p[0] * y**2, 3.0 * p[1] * yd**2


def _softplus(x, s):
    return s * np.logaddexp(0.0, x / s)


def _element_case(case):
    """(force elements, continuous right-hand side F, zdot(y, yd, z), n_z)."""
    if case == "cubic":
        return (CubicStiffness(1e10),), lambda y, yd, z: (1e10 * y**3, np.zeros(0)), 0
    if case in ("bouc_wen", "bouc_wen_nu2"):
        # nu = 2 needs gamma + delta > 0 to stay bounded (softening loop)
        alpha, beta, gamma, delta, nu = (
            (5e4, 1e3, 0.8, -1.1, 1.0) if case == "bouc_wen" else (5e4, 50.0, 0.8, -0.2, 2.0)
        )

        def rhs(y, yd, z):
            zz = z[0]
            zd = alpha * yd - beta * (gamma * abs(yd) * abs(zz) ** (nu - 1) * zz
                                      + delta * yd * abs(zz) ** nu)
            return zz, np.array([zd])
        return (BoucWen(alpha, beta, gamma, delta, nu),), rhs, 1
    if case == "quadratic":
        return (QuadraticStiffness(3e6),), lambda y, yd, z: (3e6 * y**2, np.zeros(0)), 0
    if case == "coulomb":
        return (CoulombFriction(4.0, 1e-2),), lambda y, yd, z: (4.0 * np.tanh(yd / 1e-2), np.zeros(0)), 0
    if case == "quadratic_damping":
        return (QuadraticDamping(200.0),), lambda y, yd, z: (200.0 * yd * abs(yd), np.zeros(0)), 0
    if case == "dead_zone":
        g, s = 3e-4, 1.5e-5
        return ((DeadZoneSpring(5e4, g),),
                lambda y, yd, z: (5e4 * (_softplus(y - g, s) - _softplus(-y - g, s)), np.zeros(0)), 0)
    if case == "coupled_mass":
        def rhs(y, yd, z):
            f = 2e4 * (y - z[0]) + 2.0 * (yd - z[1])
            return f, np.array([z[1], f / 0.2])
        return (CoupledMass(0.2, 2.0, 2e4),), rhs, 2
    if case == "drift":
        # the clock state z = t makes the stiffness k - 1e4 t
        return (StiffnessDrift(-1e4),), lambda y, yd, z: (-1e4 * z[0] * y, np.array([1.0])), 1
    if case == "custom":
        return ((CustomForce(_cubic_spring_and_damper, [5e9, 1.0], name="cubic"),),
                lambda y, yd, z: (5e9 * y**3 + yd**3, np.zeros(0)), 0)
    raise ValueError(case)


ELEMENT_CASES = ["cubic", "bouc_wen", "bouc_wen_nu2", "quadratic", "coulomb", "quadratic_damping",
                 "dead_zone", "coupled_mass", "drift", "custom"]


@pytest.mark.parametrize("case", ELEMENT_CASES)
def test_nonlinear_elements_follow_continuous_dynamics(case):
    fs_fine = 15000.0
    amp, f0, rate, t_end = 40.0, 20.0, 10.0, 1.0
    forces, rhs, nz = _element_case(case)
    osc = Oscillator(M, C, K, forces=forces)
    t = np.arange(int(t_end * fs_fine)) / fs_fine
    sim = osc.simulate_fine(linear_chirp(t, f_start=f0, rate=rate, amplitude=amp),
                            fs=fs_fine, periodic=False)
    assert sim.n_newton_failures == 0
    assert sim.z.shape == (t.size, nz)
    ref = _continuous_reference(rhs, nz, t_end, fs_fine, amp, f0, rate)
    err = _rel_rms(sim.y, ref)
    assert err < 1e-3, err  # Newmark at 15 kHz: measured 0.5e-4 to 1.5e-4
    # the element must matter, or the comparison above proves little
    lin = Oscillator(M, C, K).simulate_fine(sim.u, fs=fs_fine, periodic=False)
    assert _rel_rms(lin.y, ref) > 10 * err


def test_time_varying_element_refuses_periodic_and_continues_from_a_state():
    u = 10 * np.sin(2 * np.pi * 30 * np.arange(1500) / 15000.0)
    drift = Oscillator(M, C, K, forces=(StiffnessDrift(-1e4),))
    with pytest.raises(ValueError, match="periodic=False"):
        drift.simulate_fine(u, fs=15000.0, periodic=True)
    # a periodic steady state followed by a continuation equals the steady state
    osc = bouc_wen_oscillator()
    per = osc.simulate_fine(u, fs=15000.0, periodic=True)
    cont = osc.simulate_fine(np.tile(u, 2), fs=15000.0, periodic=False, initial_state=per.final_state)
    np.testing.assert_allclose(cont.y, np.tile(per.y, 2), rtol=0, atol=1e-10 * np.abs(per.y).max())
    with pytest.raises(ValueError, match="initial_state"):
        osc.simulate_fine(u, fs=15000.0, periodic=False, initial_state=np.zeros(2))


def test_custom_force_must_be_compiled():
    with pytest.raises(TypeError, match="numba.njit"):
        CustomForce(lambda p, y, yd: (0.0, 0.0, 0.0))


def test_a_users_element_reuses_the_disk_cached_integrator():
    # numba keys its disk cache by argument types. A user's function reaches
    # the kernels as a cfunc of one fixed signature, the same type in every
    # process, so the integrator compiled once serves every new function (an
    # njit function's type is new in every process: each recompiled the
    # whole integrator, and broke later saves to the cache index).
    import subprocess
    import sys

    from numba.core import types as nb_types
    from numba.core.caching import FunctionCache

    from sklearn_pnlss.physics import _newmark

    forces = (CustomForce(_cubic_spring_and_damper, [5e9, 1.0]),)
    u = 10 * np.sin(2 * np.pi * 30 * np.arange(750) / 750)
    y_custom = Oscillator(M, C, K, forces=forces).simulate(u, fs=750.0, periodic=True)
    Oscillator(M, C, K, forces=forces).restoring_force(y_custom, y_custom)
    y_plain = Oscillator(M, C, K).simulate(u, fs=750.0, periodic=True)
    assert _rel_rms(y_custom, y_plain) > 1e-3  # the custom element was called
    stable = nb_types.FunctionType(_newmark.CUSTOM_SIGNATURE)
    cached = [d for d in vars(_newmark).values() if isinstance(getattr(d, "_cache", None), FunctionCache)]
    assert any(d is _newmark._stateless_run for d in cached)  # the loop a stateless element runs in
    for kernel in cached:
        for signature in kernel.signatures:
            assert not any(isinstance(t, (nb_types.Dispatcher, nb_types.Function)) for t in signature)
            assert all(t == stable for t in signature if isinstance(t, nb_types.FunctionType)), signature
    # a new process with a function of its own loads the integrator from disk
    script = """
import numpy as np
from numba import njit
from sklearn_pnlss.physics import CustomForce, Oscillator, _newmark
@njit
def stiffening(p, y, yd):
    return p[0] * y**3, 3 * p[0] * y**2, 0.0
u = 10 * np.sin(2 * np.pi * 30 * np.arange(750) / 750)
Oscillator(%r, %r, %r, forces=(CustomForce(stiffening, [5e9]),)).simulate(u, fs=750.0, periodic=True)
loop = _newmark._stateless_run
print(sum(loop.stats.cache_misses.values()), sum(loop.stats.cache_hits.values()))
""" % (M, C, K)
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    misses, hits = map(int, run.stdout.split()[-2:])
    assert (misses, hits) == (0, 1), run.stdout + run.stderr


def test_steady_state_not_reached_warns():
    # an undamped linear oscillator never settles
    osc = Oscillator(1.0, 0.0, 1e4)
    u = np.sin(2 * np.pi * 3 * np.arange(200) / 200)
    with pytest.warns(ConvergenceWarning, match="max_periods=3"):
        sim = osc.simulate_fine(u, fs=200.0, periodic=True, max_periods=3)
    assert sim.n_periods == 3


def test_a_steady_state_that_cannot_settle_stops_early():
    """An undamped oscillator, and a hysteresis without dissipation (gamma = 0:
    its loop shifts freely), never settle: once plain periods show that the
    cap cannot be reached settled, the search stops, unsettled, with the
    warning, instead of integrating all 200 periods."""
    u = np.sin(2 * np.pi * 3 * np.arange(200) / 200)
    neutral = Oscillator(2.0, 10.0, 5e4, forces=(BoucWen(1300.0, 340.0, 0.0, 0.3, 1.0),))
    for osc, u in [(Oscillator(1.0, 0.0, 1e4), u), (neutral, 300 * _few_line_signal(512, np.arange(4, 100)))]:
        with pytest.warns(ConvergenceWarning, match="max_periods=200"):
            sim = osc.simulate_fine(u, fs=200.0 if osc is not neutral else 3750.0, periodic=True, max_periods=200)
        assert sim.n_periods <= 12


def test_a_response_beyond_max_abs_stops_after_one_period():
    osc = Oscillator(1.0, 1.0, 1e4)
    u = 1e4 * np.sin(2 * np.pi * 3 * np.arange(200) / 200)  # about 1 m
    with pytest.raises(FloatingPointError, match="max_abs=0.1"):
        osc.simulate_fine(u, fs=200.0, periodic=True, max_abs=0.1)
    with pytest.raises(FloatingPointError, match="max_abs=0.1"):
        osc.simulate_fine(u, fs=200.0, periodic=False, max_abs=0.1)
    assert osc.simulate_fine(u, fs=200.0, periodic=True, max_abs=10.0).n_periods >= 2


def test_periodic_steady_state_equals_long_run_from_rest():
    osc = bouc_wen_oscillator()
    n = 512
    u = 5 * _few_line_signal(n, np.arange(4, 100))
    u_fine = upsample_fft(u, 20, periodic=True)
    per = osc.simulate_fine(u_fine, fs=15000.0, periodic=True)
    assert per.n_periods >= 2
    rest = osc.simulate_fine(np.tile(u_fine, 40), fs=15000.0, periodic=False)
    np.testing.assert_allclose(per.y, rest.y[-u_fine.size:], rtol=0,
                               atol=1e-11 * np.abs(per.y).max())


def test_slow_steady_state_is_shot_not_waited_for():
    """A barely damped low mode decays by 4 % per period: waiting for it
    would take some 500 periods; Newton on the period map takes ten, and
    the result is the steady state a long run from rest reaches."""
    m2, w2, zeta = 0.002, 7.9, 0.001
    osc = Oscillator(M, C, K, forces=(CoupledMass(m2, 2 * zeta * m2 * w2, m2 * w2**2),))
    n = 512
    u = 5 * _few_line_signal(n, np.arange(4, 100))
    u_fine = upsample_fft(u, 4, periodic=True)
    fs = 3000.0 / 8  # a period lasts 5.5 s
    per = osc.simulate_fine(u_fine, fs=fs, periodic=True, tol=1e-10)
    assert per.n_periods <= 12
    rest = osc.simulate_fine(np.tile(u_fine, 1500), fs=fs, periodic=False)
    np.testing.assert_allclose(per.y, rest.y[-u_fine.size:], rtol=0, atol=1e-9 * np.abs(per.y).max())
    np.testing.assert_allclose(per.z, rest.z[-u_fine.size:], rtol=0, atol=1e-8 * np.abs(per.z).max())


SENSITIVITY_ELEMENTS = {
    "linear": (),
    "cubic": (CubicStiffness(1e8),),
    "quadratic": (QuadraticStiffness(1.5e6),),
    "bouc_wen": (BoucWen(1e4, 300.0, 0.8, -1.1, 1.3),),
    "coulomb": (CoulombFriction(1.0, 2e-3),),
    "quadratic_damping": (QuadraticDamping(15.0),),
    "dead_zone": (DeadZoneSpring(1e4, 1.5e-3),),
    "coupled_mass": (CoupledMass(0.2, 15.0, 0.2 * (2 * np.pi * 60) ** 2),),
    "series_damper": (SeriesDamper(30.0, 1e4),),
}


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("name", sorted(SENSITIVITY_ELEMENTS))
def test_sensitivities_are_the_derivatives_of_the_simulation(name, periodic):
    """The integrator's sensitivity recursion against central differences of
    whole simulations, by every physical parameter; periodic: the steady
    state's own derivative through the period map (the orbit moves too)."""
    forces = SENSITIVITY_ELEMENTS[name]
    n, fs = 256, 3750.0
    u_fine = upsample_fft(5 * _few_line_signal(n, np.arange(2, 40)), 5, periodic=True)  # 50 N rms
    osc = Oscillator(2.0, 10.0, 5e4, forces=forces)

    def simulate(p):
        moved = Oscillator(p[0], p[1], p[2], forces=forces)
        moved._packed[2][:] = p[3:]
        if periodic:
            return moved.simulate_fine(u_fine, fs=fs, periodic=True, tol=1e-14, max_periods=300, warn=False).y
        return moved.simulate_fine(u_fine, fs=fs, periodic=False).y

    steady = osc.simulate_fine(u_fine, fs=fs, periodic=True, tol=1e-14, max_periods=300).final_state
    y, dy = osc.sensitivity(u_fine, fs=fs, periodic=periodic, steady_state=steady if periodic else None)
    np.testing.assert_allclose(y, simulate(osc.parameter_vector), rtol=0, atol=1e-9 * np.abs(y).max())
    p0 = osc.parameter_vector
    for i in range(p0.size):
        step = 1e-6 * abs(p0[i])
        up, down = p0.copy(), p0.copy()
        up[i] += step
        down[i] -= step
        fd = (simulate(up) - simulate(down)) / (2 * step)
        # the corner scales of the smoothed elements (a friction's velocity
        # scale, a dead zone's smoothing) are the parameters whose central
        # differences are themselves only good to about 1e-4
        tol = 1e-3 if (name, i) in (("coulomb", 4), ("dead_zone", 5)) else 1e-4
        assert np.linalg.norm(dy[:, i] - fd) <= tol * np.linalg.norm(fd), (name, i)


def test_sensitivity_refuses_what_it_cannot_differentiate():
    osc = Oscillator(2.0, 10.0, 5e4, forces=(StiffnessDrift(-1.0),))
    with pytest.raises(ValueError, match="time-invariant"):
        osc.sensitivity(np.ones(64), fs=1000.0, periodic=True, steady_state=np.zeros(5))


def test_noise_is_band_limited_and_shaped_by_decimation():
    osc = Oscillator(M, C, K)
    u = _few_line_signal(8192, np.arange(55, 1639))
    clean = osc.simulate(u, fs=750.0, periodic=True)
    noisy = osc.simulate(u, fs=750.0, periodic=True, noise_rms=8e-6, random_state=0)
    e = noisy - clean
    assert np.sqrt(np.mean(e**2)) == pytest.approx(7.4e-6, rel=0.03)
    again = osc.simulate(u, fs=750.0, periodic=True, noise_rms=8e-6, random_state=0)
    np.testing.assert_array_equal(noisy, again)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(decimation=(2, 5)), "decimation"),
        (dict(decimation=()), "decimation"),
        (dict(oversampling=0), "oversampling"),
        (dict(fs=0.0), "fs"),
        (dict(noise_rms=-1.0), "noise_rms"),
        (dict(u_fine=np.zeros(10)), "u_fine"),
        (dict(u=np.zeros(10)), "too short"),
    ],
)
def test_simulate_errors(kwargs, match):
    osc = bouc_wen_oscillator()
    args = dict(u=np.zeros(1000), fs=750.0, periodic=False)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        osc.simulate(**args)


def test_input_errors():
    osc = bouc_wen_oscillator()
    with pytest.raises(ValueError, match="u must be 1-D"):
        osc.simulate(np.zeros((1000, 1)), fs=750.0, periodic=False)
    with pytest.raises(ValueError, match="u contains NaN"):
        osc.simulate(np.r_[np.zeros(999), np.inf], fs=750.0, periodic=False)
    with pytest.raises(ValueError, match="mass"):
        Oscillator(0.0, 1.0, 1.0)
    with pytest.raises(TypeError, match="forces"):
        Oscillator(1.0, 1.0, 1.0, forces=("bouc-wen",))
    with pytest.raises(ValueError, match="nu"):
        BoucWen(nu=0.5)


# ------------------------------------------------- fidelity to official files
def _load(folder, name):
    return loadmat(folder / f"{name}.mat")[name].ravel()


def test_official_multisine_reproduced(bouc_wen_dir):
    u = _load(bouc_wen_dir, "uval_multisine")
    y = _load(bouc_wen_dir, "yval_multisine")
    err = _rel_rms(simulate_bouc_wen(u, periodic=True), y)
    assert err < 1e-11, err  # measured 3.8e-13


def test_official_sweep_reproduced(bouc_wen_dir):
    u = _load(bouc_wen_dir, "uval_sinesweep")
    y = _load(bouc_wen_dir, "yval_sinesweep")
    err = _rel_rms(simulate_bouc_wen(u, periodic=False, decimation=(20,)), y)
    assert err < 1e-7, err  # measured 4.1e-8 (FFT interpolation of the input)
    osc = bouc_wen_oscillator()
    exact = osc.simulate(u, fs=750.0, periodic=False, decimation=(20,),
                         u_fine=bouc_wen_sweep(u.size, oversampling=20))
    err_exact = _rel_rms(exact, y)
    assert err_exact < 1e-11, err_exact  # measured 8.5e-13
    # the 2-2-5 chain is measurably not what produced the sweep file
    assert _rel_rms(simulate_bouc_wen(u, periodic=False), y) > 1e-3


def test_official_training_record_procedure(bouc_wen_dir):
    data = loadmat(bouc_wen_dir / "train_multisine_official.mat")
    u, y = data["u"].ravel(), data["y"].ravel()
    n = 8192
    np.testing.assert_array_equal(u[:n], u[n:2 * n])
    # 6 periods from rest at 15 kHz, 2-2-5 chain, last period dropped
    u_fine = np.tile(upsample_fft(u[:n], 20, periodic=True), 6)
    sim = bouc_wen_oscillator().simulate_fine(u_fine, fs=15000.0, periodic=False)
    y_sim = decimate_fir(sim.y, (2, 2, 5))[: 5 * n]
    noise = np.sqrt(np.mean((y - y_sim) ** 2))
    assert noise == pytest.approx(7.4e-6, rel=0.02), noise  # measured 7.37e-6


FAST_PATH_ELEMENTS = {
    "linear": (),
    "cubic and friction": (CubicStiffness(3e7), CoulombFriction(1.0, 2e-3)),
    "hysteresis": (BoucWen(1e4, 300.0, 0.8, -1.1, 1.0),),
    "second mode and damping": (QuadraticDamping(5.0), CoupledMass(0.2, 15.0, 0.2 * (2 * np.pi * 60) ** 2)),
    "two one-state elements": (BoucWen(1e4, 300.0, 0.8, -1.1, 1.0), SeriesDamper(30.0, 1e4)),
}


@pytest.mark.parametrize("name", sorted(FAST_PATH_ELEMENTS))
def test_scalar_loops_equal_the_general_loop_to_the_bit(name):
    """Without sensitivities, up to two internal states run on scalar loops
    (``_stateless_run``, ``_one_state_run``, ``_two_state_run``); with one
    sensitivity direction the same steps run in the general loop, whose
    path the direction does not change: the motions must be identical."""
    from sklearn_pnlss.physics import oscillator

    osc = Oscillator(2.0, 10.0, 5e4, forces=FAST_PATH_ELEMENTS[name])
    kinds, p_off, params, z_off, _ = osc._packed
    nz = osc.n_internal_states
    u = upsample_fft(5 * _few_line_signal(512, np.arange(2, 60)), 5, periodic=True)
    runs = []
    for n_dir in (0, 1):
        state = np.zeros(oscillator.STATE_Z + 2 * nz)
        state[0] = 1e-4
        y, yd, z = np.empty(u.size), np.empty(u.size), np.empty((u.size, nz))
        tangents = np.zeros((n_dir, state.size))
        osc._newmark_run(u, u.size - 1, 1 / 3750.0, osc.mass, osc.damping, osc.stiffness, kinds, p_off, params,
                         z_off, state, True, y, yd, z, oscillator._NEWTON_RTOL, oscillator._NEWTON_MAX_ITER,
                         tangents, np.zeros(n_dir, dtype=np.int64), np.zeros((u.size, n_dir)))
        runs.append((y, yd, z, state))
    assert np.abs(runs[0][0]).max() > 1e-4  # a motion, not rest
    for fast, general in zip(*runs):
        np.testing.assert_array_equal(fast, general)


def _joint_elimination(a, b, n):
    """Gaussian elimination with partial pivoting of the matrix and the
    right-hand side together (the integrator's solve before it factored
    once per step); the solution overwrites b."""
    for col in range(n):
        piv = col
        best = abs(a[col, col])
        for r in range(col + 1, n):
            if abs(a[r, col]) > best:
                best, piv = abs(a[r, col]), r
        if piv != col:
            a[[col, piv]] = a[[piv, col]]
            b[col], b[piv] = b[piv], b[col]
        for r in range(col + 1, n):
            f = a[r, col] / a[col, col]
            if f != 0.0:
                for j in range(col, n):
                    a[r, j] -= f * a[col, j]
                b[r] -= f * b[col]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for j in range(r + 1, n):
            s -= a[r, j] * b[j]
        b[r] = s / a[r, r]


def test_a_factored_matrix_solves_as_the_full_elimination():
    """The integrator's one factorisation per step, replayed per right-hand
    side, and the scalar 3 x 3 solve give the joint elimination's numbers to
    the bit, pivoting included."""
    from sklearn_pnlss.physics._newmark import _factor_inplace, _solve3, _solve_factored

    rng = np.random.default_rng(0)
    for trial in range(300):
        n = 2 + trial % 4
        a = rng.standard_normal((n, n)) * 10.0 ** rng.integers(-3, 4, (n, n))
        if trial % 5 == 0:
            a[1:, 0] = 0.0  # zero multipliers are skipped
        b = rng.standard_normal(n)
        expected = b.copy()
        _joint_elimination(a.copy(), expected, n)
        factored, pivots = a.copy(), np.zeros(n, dtype=np.int64)
        _factor_inplace.py_func(factored, pivots, n)
        got = b.copy()
        _solve_factored.py_func(factored, pivots, got, n)
        np.testing.assert_array_equal(got, expected)
        if n == 3:
            np.testing.assert_array_equal(np.array(_solve3.py_func(*a.ravel(), *b)), expected)
