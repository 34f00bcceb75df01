"""Single-degree-of-freedom oscillator simulated the way the benchmark was."""
import warnings
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np
from scipy import fft as sp_fft
from sklearn.exceptions import ConvergenceWarning
from sklearn.utils import check_random_state

from ._newmark import STATE_Z, custom_dispatcher, newmark_run, stateless_forces
from ._shooting import PeriodShooter
from .forces import KIND_CUSTOM, pack_forces
from .resampling import check_factors, check_signal, decimate_fir, upsample_fft

# STATE_Z is public: the index of the first internal state in an integrator
# state vector (FineSimulation.final_state, simulate_fine's initial_state),
# for callers that build such a state themselves.
__all__ = ["Oscillator", "FineSimulation", "band_limited_noise", "STATE_Z"]

# Newton stops when every update is below this fraction of the unknown's
# running magnitude: round-off level, because the benchmark files were
# produced by a fully converged solve.
_NEWTON_RTOL = 1e-13
_NEWTON_MAX_ITER = 60
# Periods simulated plainly before (and between) Newton steps on the
# periodic steady state: a well-damped structure settles before.
_SHOOT_AFTER = 3
# Sensitivity arguments of a plain run: no directions.
_NO_TANGENTS = np.zeros((0, 0))
_NO_PARAMS = np.zeros(0, dtype=np.int64)


@dataclass
class FineSimulation:
    """States of an oscillator simulation at the integration rate.

    Attributes
    ----------
    t : ndarray of shape (n,)
        Times, ``i / fs``.
    u, y, yd : ndarray of shape (n,)
        Input force, displacement and velocity.
    z : ndarray of shape (n, n_internal_states)
        Internal states of the force elements, in the order of ``forces``.
    fs : float
        Integration rate.
    n_periods : int
        Periods simulated, the returned one included (1 if not periodic).
    n_newton_failures : int
        Steps where Newton-Raphson did not reach full convergence.
    final_state : ndarray or None
        The integrator's state after the last step: for a periodic
        simulation, the steady state at the first sample of the next period,
        to continue from with ``simulate_fine(..., initial_state=...)``.
        Laid out as ``[y, yd, ydd, z_0, ..., z_{nz-1}, zd_0, ..., zd_{nz-1}]``;
        the internal states start at index ``STATE_Z`` of this module.
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    yd: np.ndarray
    z: np.ndarray
    fs: float
    n_periods: int
    n_newton_failures: int
    final_state: np.ndarray = None


def _positive_real(name, value, *, allow_zero=False):
    if isinstance(value, bool) or not isinstance(value, Real) or not np.isfinite(value):
        raise ValueError(f"{name} must be a finite real number, got {value!r}.")
    if value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be {bound}, got {value!r}.")
    return float(value)


def _check_bound(y, max_abs):
    """Raise when a displacement record exceeds ``max_abs`` (None: no bound)."""
    if max_abs is not None and np.max(np.abs(y)) > max_abs:
        raise FloatingPointError(
            f"the displacement exceeded max_abs={max_abs:g} (peak {np.max(np.abs(y)):g}): the response runs away."
        )


def _futile(changes, tol, periods_left):
    """Whether plain periods whose changes shrink as ``changes`` do cannot
    settle to ``tol`` in ``periods_left`` more: the rate is read over the
    last two periods.  A neutral mode (a hysteresis without dissipation
    shifts its loop freely) or a chaotic response then stops at once
    instead of running to ``max_periods``, which it would reach unsettled."""
    if len(changes) < 3 or changes[-3] <= 0:
        return False
    rate = np.sqrt(changes[-1] / changes[-3])
    return rate >= 1.0 or changes[-1] * rate**periods_left > tol


def _check_decimation(decimation, oversampling):
    decimation = check_factors(decimation, "decimation")
    if int(np.prod(decimation)) != oversampling:
        raise ValueError(
            f"the product of decimation {decimation} is {int(np.prod(decimation))}, "
            f"it must equal oversampling={oversampling}."
        )
    return decimation


def band_limited_noise(n_samples, *, fs, f_max, rms, random_state=None):
    """Gaussian noise band-limited to ``[0, f_max]`` by zeroing FFT bins.

    Parameters
    ----------
    n_samples : int
        Number of samples.
    fs : float
        Sampling rate of the noise, Hz.
    f_max : float
        Highest kept frequency, Hz (bins above it are set to zero).
    rms : float
        Exact rms of the returned record.
    random_state : int, RandomState instance or None, default=None
        Seed of the Gaussian draw.

    Returns
    -------
    noise : ndarray of shape (n_samples,)

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.physics import band_limited_noise
    >>> e = band_limited_noise(15000, fs=15000.0, f_max=375.0, rms=1e-3,
    ...                        random_state=0)
    >>> round(float(np.sqrt(np.mean(e**2))), 9)
    0.001
    """
    rng = check_random_state(random_state)
    white = rng.standard_normal(n_samples)
    spec = sp_fft.rfft(white)
    freqs = np.arange(spec.size) * fs / n_samples
    spec[freqs > f_max] = 0.0
    noise = sp_fft.irfft(spec, n_samples)
    power = np.sqrt(np.mean(noise**2))
    return noise * (rms / power) if power > 0 else noise


class Oscillator:
    r"""Single-degree-of-freedom oscillator with nonlinear force elements.

    .. math:: m \ddot y + c \dot y + k y + \sum_e F_e(y, \dot y, z_e) = u,
              \qquad \dot z_e = g_e(y, \dot y, z_e)

    Integrated as the Bouc-Wen benchmark data were: Newmark average
    acceleration for ``y``, trapezoidal rule for ``z``, fully converged
    Newton-Raphson per step, at ``oversampling`` times the data rate; the
    output is brought back to the data rate by MATLAB-compatible FIR
    decimation.

    Parameters
    ----------
    mass : float
        Mass ``m`` (kg), > 0.
    damping : float
        Viscous damping ``c`` (N s/m), >= 0.
    stiffness : float
        Linear stiffness ``k`` (N/m).
    forces : sequence of ForceElement, default=()
        Nonlinear force elements, e.g. ``(BoucWen(),)``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.physics import Oscillator, BoucWen
    >>> osc = Oscillator(2.0, 10.0, 5e4, forces=(BoucWen(),))
    >>> u = 10 * np.sin(2 * np.pi * 30 * np.arange(750) / 750)
    >>> y = osc.simulate(u, fs=750.0, periodic=True)
    >>> y.shape
    (750,)
    """

    def __init__(self, mass, damping, stiffness, forces=()):
        self.mass = _positive_real("mass", mass)
        self.damping = _positive_real("damping", damping, allow_zero=True)
        if isinstance(stiffness, bool) or not isinstance(stiffness, Real) or not np.isfinite(stiffness):
            raise ValueError(f"stiffness must be a finite real number, got {stiffness!r}.")
        self.stiffness = float(stiffness)
        self.forces = tuple(forces)
        self._packed = pack_forces(self.forces)

    def __repr__(self):
        return (
            f"Oscillator(mass={self.mass!r}, damping={self.damping!r}, "
            f"stiffness={self.stiffness!r}, forces={self.forces!r})"
        )

    @property
    def n_internal_states(self):
        """Total number of internal states of the force elements."""
        return int(self._packed[3][-1])

    @property
    def time_varying(self):
        """True when a force element depends on time (no periodic steady state)."""
        return any(f.time_varying for f in self.forces)

    def _newmark_run(self, *args):
        """The integrator's kernel (:func:`._newmark.newmark_run`) with this
        oscillator's custom elements."""
        return newmark_run(*args, custom_dispatcher(self._packed[4]))

    def _stateless_forces(self, *args):
        """The stateless elements' forces along a motion, custom ones included."""
        return stateless_forces(*args, custom_dispatcher(self._packed[4]))

    def restoring_force(self, y, yd):
        """The force ``c yd + k y + sum_e F_e(y, yd)`` of the elements without
        internal states, along a motion (the stateful ones, e.g. Bouc-Wen,
        need their state history and are left out).

        Parameters
        ----------
        y, yd : ndarray of shape (n,)
            Displacement and velocity.

        Returns
        -------
        force : ndarray of shape (n,)
        """
        y = np.ascontiguousarray(y, dtype=np.float64)
        yd = np.ascontiguousarray(yd, dtype=np.float64)
        kinds, p_off, params, z_off, _ = self._packed
        return self.damping * yd + self.stiffness * y + self._stateless_forces(
            kinds, p_off, params, z_off, y, yd)

    def with_forces(self, forces, **linear):
        """A copy with other force elements (and optionally other ``mass``,
        ``damping`` or ``stiffness``)."""
        params = dict(mass=self.mass, damping=self.damping, stiffness=self.stiffness)
        params.update(linear)
        return Oscillator(forces=tuple(forces), **params)

    # ------------------------------------------------------------------
    def _run(self, u_fine, n_steps, h, state, init_accel, n_out):
        kinds, p_off, params, z_off, _ = self._packed
        y = np.empty(n_out)
        yd = np.empty(n_out)
        z = np.empty((n_out, self.n_internal_states))
        n_failed, _ = self._newmark_run(
            u_fine, n_steps, h, self.mass, self.damping, self.stiffness,
            kinds, p_off, params, z_off, state, init_accel, y, yd, z,
            _NEWTON_RTOL, _NEWTON_MAX_ITER, _NO_TANGENTS, _NO_PARAMS, _NO_TANGENTS,
        )
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(state))):
            raise FloatingPointError(
                "the simulation diverged (non-finite state); check the input "
                "amplitude and the oscillator parameters."
            )
        return y, yd, z, int(n_failed)

    def simulate_fine(self, u_fine, *, fs, periodic, tol=1e-12, max_periods=200,
                      initial_state=None, warn=True, max_abs=None):
        """Simulate at the integration rate and return all states.

        Parameters
        ----------
        u_fine : array-like of shape (n_samples,)
            Input force at the integration rate ``fs``.
        fs : float
            Integration rate, Hz (step ``h = 1 / fs``).
        periodic : bool
            If True, ``u_fine`` is one period of a periodic input: periods are
            simulated from rest (or ``initial_state``) until the state at the
            end of a period differs from its start by less than ``tol``
            (relative to the state's peak over the period); the last period
            is returned.  If False, the simulation starts from rest (or
            ``initial_state``) at ``t = 0``.
        tol : float, default=1e-12
            Steady-state tolerance (periodic only).
        max_periods : int, default=200
            Cap on the number of simulated periods; a
            :class:`~sklearn.exceptions.ConvergenceWarning` is issued when the
            steady state is not reached.
        initial_state : ndarray, default=None
            Start from this integrator state instead of rest: the state at
            the first sample, whose input must be ``u_fine[0]``.  The
            ``final_state`` of a periodic simulation is such a state for the
            next period (it holds the same oscillator's layout of
            displacement, velocity, acceleration and internal states; the
            acceleration and the states' rates are recomputed from the
            equation of motion).  With ``periodic`` the steady-state search
            starts there: where several steady states coexist (a stiffening
            spring driven above its resonance), the one whose basin holds
            this state is found.
        warn : bool, default=True
            Warn when the steady state is not reached (callers that check
            ``n_periods`` themselves turn it off).
        max_abs : float, default=None
            Raise ``FloatingPointError`` once the displacement exceeds this
            bound (checked after each period, or at the end of a
            non-periodic run).  A fit's trial point whose response runs away
            is then rejected after one period, not after ``max_periods``.

        Returns
        -------
        sim : FineSimulation
        """
        u_fine = check_signal(u_fine, "u_fine")
        fs = _positive_real("fs", fs)
        if u_fine.size < 2:
            raise ValueError(f"u_fine must have at least 2 samples, got {u_fine.size}.")
        h = 1.0 / fs
        n = u_fine.size
        nz = self.n_internal_states
        state = np.zeros(STATE_Z + 2 * nz)
        if initial_state is not None:
            initial_state = np.asarray(initial_state, dtype=np.float64)
            if initial_state.shape != state.shape or not np.all(np.isfinite(initial_state)):
                raise ValueError(
                    f"initial_state must be a finite final_state of this oscillator "
                    f"(shape {state.shape}), got shape {initial_state.shape}."
                )
            # The acceleration and the internal states' rates follow from
            # (y, yd, z) and u_fine[0]: recompute them, so a caller only has
            # to supply the positions (e.g. a clock state set to zero).
            state = initial_state.copy()
        if not periodic:
            y, yd, z, n_failed = self._run(u_fine, n - 1, h, state, True, n)
            _check_bound(y, max_abs)
            return FineSimulation(np.arange(n) * h, u_fine, y, yd, z, fs, 1, n_failed, state)
        if self.time_varying:
            raise ValueError(
                "a time-varying force element (e.g. StiffnessDrift) has no periodic "
                "steady state: simulate with periodic=False."
            )

        if not (np.isfinite(tol) and tol > 0):
            raise ValueError(f"tol must be a positive number, got {tol!r}.")
        if isinstance(max_periods, bool) or not isinstance(max_periods, Integral) or max_periods < 1:
            raise ValueError(f"max_periods must be a positive int, got {max_periods!r}.")
        init = True
        total_failed = 0
        converged = False
        # After a few unsettled periods, Newton steps on the period map (see
        # _shooting): a slowly decaying structure needs a handful of
        # periods instead of hundreds.
        exact = None if np.any(self._packed[0] == KIND_CUSTOM) else (
            lambda st, idx: self._period_jacobian(u_fine, n, h, st, idx))
        shooter = PeriodShooter(lambda st, ini: self._run(u_fine, n, h, st, ini, n)[:3], state.size, nz, exact)
        period, resume, plain = 0, None, []
        while period < max_periods:
            start = state.copy()
            try:
                y, yd, z, n_failed = self._run(u_fine, n, h, state, init, n)
            except FloatingPointError:
                if resume is None:
                    raise
                # the shot diverged: carry on plainly from the period before
                state, init, resume, shooter.active = resume, False, None, False
                continue
            period += 1
            init = False
            total_failed += n_failed
            _check_bound(y, max_abs)
            change = self._change(start, state, y, yd, z)
            if period > 1 and change <= tol:
                converged = True
                break
            if not shooter.active:
                plain.append(change)
                if _futile(plain, tol, max_periods - period):
                    break
            if period >= _SHOOT_AFTER and period < max_periods:
                shot, used = shooter.step(start, state, [y, yd] + [z[:, j] for j in range(nz)],
                                          max_periods - period - 1)
                period += used
                if shot is not None:
                    state, init, resume = shot, True, state.copy()
        if not converged and warn:
            warnings.warn(
                f"periodic steady state not reached within max_periods={max_periods} "
                f"periods (tolerance {tol:g}); the last period is returned.",
                ConvergenceWarning,
                stacklevel=2,
            )
        return FineSimulation(np.arange(n) * h, u_fine, y, yd, z, fs, period, total_failed, state)

    @property
    def parameter_vector(self):
        """The physical parameters :meth:`sensitivity` differentiates by:
        mass, damping, stiffness, then each force element's parameters in
        the order of ``forces`` (each element's ``params``)."""
        return np.concatenate([[self.mass, self.damping, self.stiffness], self._packed[2]])

    def sensitivity(self, u_fine, *, fs, periodic, steady_state=None):
        """Displacement and its exact derivatives by every physical parameter.

        The derivatives are those of the integration scheme itself: each
        converged step's equations are differentiated and solved with its
        Newton matrix, along with the simulation (one run instead of one
        per parameter).  A periodic steady state moves with the parameters
        too: the period is run once more with the initial state's
        directions as well, and the orbit's own derivative solved from the
        period map, ``(I - Phi) s_0 = b``.

        Parameters
        ----------
        u_fine : array-like of shape (n_samples,)
            Input force at the integration rate.
        fs : float
            Integration rate, Hz.
        periodic : bool
            False: from rest at ``t = 0``.  True: ``u_fine`` is one period
            and ``steady_state`` the ``final_state`` of a periodic
            :meth:`simulate_fine` of it that reached its steady state.
        steady_state : ndarray, default=None
            Required with ``periodic``.

        Returns
        -------
        y : ndarray of shape (n_samples,)
        dy : ndarray of shape (n_samples, n_parameters)
            Derivatives by :attr:`parameter_vector`.

        Examples
        --------
        >>> import numpy as np
        >>> from sklearn_pnlss.physics import Oscillator, CubicStiffness
        >>> osc = Oscillator(2.0, 10.0, 5e4, forces=(CubicStiffness(1e8),))
        >>> u = 50.0 * np.sin(2 * np.pi * np.arange(3000) / 3000 * 40)
        >>> y, dy = osc.sensitivity(u, fs=15000.0, periodic=False)
        >>> dy.shape
        (3000, 4)
        """
        u_fine = check_signal(u_fine, "u_fine")
        fs = _positive_real("fs", fs)
        kinds = self._packed[0]
        if np.any(kinds == KIND_CUSTOM):
            raise ValueError("sensitivity needs the built-in force elements; an oscillator with a user's "
                             "element is differenced instead.")
        n, nz = u_fine.size, self.n_internal_states
        n_state, n_params = STATE_Z + 2 * nz, 3 + self._packed[2].size
        if not periodic:
            tangents = np.zeros((n_params, n_state))
            y, dy = self._run_tangents(u_fine, n - 1, 1.0 / fs, np.zeros(n_state), True, n, tangents,
                                       np.arange(n_params))
            return y, dy
        if self.time_varying or steady_state is None:
            raise ValueError("a periodic sensitivity needs a time-invariant oscillator and the steady_state "
                             "of a converged periodic simulate_fine.")
        # Directions: each of the initial state's (the period map's Jacobian
        # Phi), then each parameter's from the same start (b).
        tangents = np.zeros((n_state + n_params, n_state))
        tangents[:n_state] = np.eye(n_state)
        param_of = np.concatenate([np.full(n_state, -1), np.arange(n_params)])
        y, dy = self._run_tangents(u_fine, n, 1.0 / fs, np.array(steady_state, float), False, n, tangents,
                                   param_of)
        phi, b = tangents[:n_state].T, tangents[n_state:].T
        start = np.linalg.solve(np.eye(n_state) - phi, b)
        return y, dy[:, n_state:] + dy[:, :n_state] @ start

    def _period_jacobian(self, u_fine, n, h, state, idx):
        """Derivatives of the positions ``idx`` of the state after one
        period from ``state`` by the same positions at its start (the
        acceleration and the rates recomputed from the equation of motion,
        as a shot is started)."""
        tangents = np.zeros((idx.size, state.size))
        tangents[np.arange(idx.size), idx] = 1.0
        self._run_tangents(u_fine, n, h, state.copy(), True, 0, tangents, np.full(idx.size, -1))
        return tangents[:, idx].T

    def _run_tangents(self, u_fine, n_steps, h, state, init_accel, n_out, tangents, param_of):
        kinds, p_off, params, z_off, _ = self._packed
        y = np.empty(n_out)
        dy = np.empty((n_out, tangents.shape[0]))
        self._newmark_run(u_fine, n_steps, h, self.mass, self.damping, self.stiffness, kinds, p_off, params,
                          z_off, state, init_accel, y, np.empty(n_out), np.empty((n_out, self.n_internal_states)),
                          _NEWTON_RTOL, _NEWTON_MAX_ITER, tangents, param_of.astype(np.int64), dy)
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(dy))):
            raise FloatingPointError("the simulation or its sensitivities diverged (non-finite state).")
        return y, dy

    @staticmethod
    def _change(start, end, y, yd, z):
        """Largest change of a position over one period, relative to its
        peak over the period (the acceleration and the rates follow from
        (y, yd, z) and u: no separate check)."""
        nz = z.shape[1]
        pairs = [(0, y), (1, yd)] + [(STATE_Z + j, z[:, j]) for j in range(nz)]
        return max(abs(end[idx] - start[idx]) / max(np.max(np.abs(trace)), 1e-300) for idx, trace in pairs)

    def simulate(self, u, *, fs, periodic, oversampling=20, decimation=(2, 2, 5),
                 noise_rms=0.0, random_state=None, u_fine=None):
        """Simulate the output at the data rate.

        The input is interpolated to ``oversampling * fs`` by FFT (exact for
        a periodic band-limited input; point-reflected extension otherwise),
        integrated there, optional band-limited noise (0 to ``fs / 2``) is
        added to the fine-rate displacement, and the result is decimated by
        the FIR chain ``decimation`` (circularly when periodic).

        Parameters
        ----------
        u : array-like of shape (n_samples,)
            Input force at rate ``fs`` (one period when ``periodic``).
        fs : float
            Data rate, Hz.
        periodic : bool
            True: return the periodic steady-state response to ``u`` repeated
            forever.  False: start from rest at ``t = 0``.
        oversampling : int, default=20
            Integration rate divided by ``fs``.
        decimation : sequence of int, default=(2, 2, 5)
            FIR decimation chain; its product must equal ``oversampling``.
        noise_rms : float, default=0.0
            Rms (at the integration rate, before decimation) of Gaussian
            output noise band-limited to ``fs / 2``.
        random_state : int, RandomState instance or None, default=None
            Seed of the noise.
        u_fine : array-like of shape (n_samples * oversampling,), default=None
            Input at the integration rate, used instead of interpolating
            ``u`` (e.g. a swept sine evaluated exactly from its formula).

        Returns
        -------
        y : ndarray of shape (n_samples,)
            Displacement at rate ``fs``.
        """
        u = check_signal(u, "u")
        fs = _positive_real("fs", fs)
        if isinstance(oversampling, bool) or not isinstance(oversampling, Integral) or oversampling < 1:
            raise ValueError(f"oversampling must be a positive int, got {oversampling!r}.")
        oversampling = int(oversampling)
        decimation = _check_decimation(decimation, oversampling)
        noise_rms = _positive_real("noise_rms", noise_rms, allow_zero=True)
        n = u.size
        if n < 4:
            raise ValueError(f"u must have at least 4 samples, got {n}.")
        if not periodic:
            # MATLAB's reflection needs more than 62 samples at every stage.
            length = n * oversampling
            for r in decimation[:-1]:
                length = -(-length // r)
            if length <= 62 and decimation[-1] > 1:
                raise ValueError(
                    f"u is too short ({n} samples) for the decimation chain "
                    f"{decimation}: the last stage would get {length} <= 62 samples."
                )
        if u_fine is None:
            u_fine = upsample_fft(u, oversampling, periodic=periodic)
        else:
            u_fine = check_signal(u_fine, "u_fine")
            if u_fine.size != n * oversampling:
                raise ValueError(
                    f"u_fine must have len(u) * oversampling = {n * oversampling} "
                    f"samples, got {u_fine.size}."
                )
        sim = self.simulate_fine(u_fine, fs=fs * oversampling, periodic=periodic)
        if sim.n_newton_failures:
            warnings.warn(
                f"Newton-Raphson did not fully converge in {sim.n_newton_failures} "
                f"integration steps; the output may be slightly inaccurate.",
                ConvergenceWarning,
                stacklevel=2,
            )
        y_fine = sim.y
        if noise_rms > 0:
            y_fine = y_fine + band_limited_noise(
                y_fine.size, fs=fs * oversampling, f_max=fs / 2, rms=noise_rms,
                random_state=random_state,
            )
        return decimate_fir(y_fine, decimation, periodic=periodic)
