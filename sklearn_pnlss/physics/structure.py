"""A linear structure of several degrees of freedom with nonlinear connections.

The structure is given by its mass, damping and stiffness matrices, or by
its modes (frequencies, damping ratios and mass-normalised shapes at the
points that matter).  Either way it has named *points*: forces enter at
points, sensors measure a point's displacement, velocity or acceleration,
and every nonlinear element is a :class:`Connection` between two points, or
between a point and the ground, acting on their relative motion.
"""
import warnings
from dataclasses import dataclass
from numbers import Integral

import numpy as np
from sklearn.exceptions import ConvergenceWarning

from ._shooting import PeriodShooter
from ._structure_run import structure_run
from .forces import KIND_CUSTOM, ForceElement, pack_forces
from .oscillator import _NEWTON_MAX_ITER, _NEWTON_RTOL, _SHOOT_AFTER, _check_bound, _futile, _positive_real
from .resampling import check_signal, decimate_columns, upsample_fft

__all__ = ["Connection", "Structure", "StructureSimulation", "SENSOR_KINDS"]

#: What a sensor measures at its point.
SENSOR_KINDS = ("displacement", "velocity", "acceleration")


@dataclass(frozen=True)
class Connection:
    """A force element acting on the relative motion of two points.

    Parameters
    ----------
    element : ForceElement
        The force law, e.g. ``CubicStiffness(1e7)``, with ``y`` the
        displacement of ``point`` less that of ``other``.
    point : str
        Where the element acts.
    other : str or None, default=None
        The point it connects ``point`` to; None: the ground.

    Examples
    --------
    >>> from sklearn_pnlss.physics import Connection, CubicStiffness
    >>> Connection(CubicStiffness(1e7), "wing", "payload").other
    'payload'
    """

    element: ForceElement
    point: str
    other: str = None

    def __post_init__(self):
        if not isinstance(self.element, ForceElement):
            raise TypeError(f"element must be a ForceElement (e.g. CubicStiffness(1e7)), got {self.element!r}.")
        if self.element.kind == KIND_CUSTOM:
            raise ValueError("a Connection takes the built-in force elements; a CustomForce acts on a "
                             "single Oscillator only.")
        if self.element.time_varying:
            raise ValueError("a Connection takes time-invariant force elements; a StiffnessDrift acts on a "
                             "single Oscillator only.")
        if self.other is not None and self.other == self.point:
            raise ValueError(f"a Connection joins two different points, got {self.point!r} twice.")


@dataclass
class StructureSimulation:
    """Motion of a structure at the integration rate.

    Attributes
    ----------
    y, yd, ydd : ndarray of shape (n_samples, n_dof)
        Displacement, velocity and acceleration of the degrees of freedom
        (modal coordinates for a structure given by its modes).
    z : ndarray of shape (n_samples, n_internal_states)
        Internal states of the connections' elements.
    fs : float
        Integration rate.
    n_periods : int
        Periods simulated, the returned one included (1 if not periodic).
    n_newton_failures : int
        Steps where Newton-Raphson did not reach full convergence.
    final_state : ndarray
        The integrator's state after the last step,
        ``[y, yd, ydd, z, zd]``, to continue from.
    """

    y: np.ndarray
    yd: np.ndarray
    ydd: np.ndarray
    z: np.ndarray
    fs: float
    n_periods: int
    n_newton_failures: int
    final_state: np.ndarray


def _square(name, value, n=None):
    a = np.atleast_2d(np.asarray(value, dtype=np.float64))
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {np.shape(value)}.")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} must be {n} x {n} like mass, got shape {a.shape}.")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values.")
    return a


class Structure:
    r"""Linear structure with nonlinear connections between its points.

    .. math:: M \ddot q + C \dot q + K q + \sum_c d_c\, F_c(d_c^T q,
              d_c^T \dot q, z_c) = \sum_i \phi_i^T u_i

    where ``q`` are the degrees of freedom, row ``phi_p`` of the point
    matrix gives point ``p``'s displacement ``phi_p q``, and
    ``d_c = phi_a - phi_b`` for a connection between points ``a`` and ``b``
    (``phi_a`` for one to the ground).  Integrated as :class:`Oscillator`
    is: Newmark average acceleration, trapezoidal internal states, a fully
    converged Newton step; only the connections' relative motions and
    states are Newton's unknowns.

    Parameters
    ----------
    mass, damping, stiffness : array-like of shape (n_dof, n_dof)
        Symmetric matrices (a number for one degree of freedom); ``mass``
        positive definite.
    points : sequence of str, default=None
        Names of the degrees of freedom, which are the points (default
        ``"0"``, ``"1"``, ...).
    connections : sequence of Connection, default=()

    Examples
    --------
    Two masses in a chain, a cubic spring between them, accelerometers on
    both:

    >>> import numpy as np
    >>> from sklearn_pnlss.physics import Connection, CubicStiffness, Structure
    >>> k = 4e4
    >>> chain = Structure(np.diag([2.0, 1.0]), np.array([[20.0, -5.0], [-5.0, 5.0]]),
    ...                   np.array([[2 * k, -k], [-k, k]]), points=["base", "tip"],
    ...                   connections=[Connection(CubicStiffness(1e9), "tip", "base")])
    >>> u = 20 * np.sin(2 * np.pi * 15 * np.arange(2000) / 2000)
    >>> a = chain.simulate(u, fs=2000.0, inputs=["base"],
    ...                    sensors=[("base", "acceleration"), ("tip", "acceleration")])
    >>> a.shape
    (2000, 2)
    """

    def __init__(self, mass, damping, stiffness, *, points=None, connections=()):
        self.mass = _square("mass", mass)
        n = self.mass.shape[0]
        self.damping = _square("damping", damping, n)
        self.stiffness = _square("stiffness", stiffness, n)
        if np.any(np.linalg.eigvalsh(0.5 * (self.mass + self.mass.T)) <= 0):
            raise ValueError("mass must be positive definite.")
        self.points = tuple(str(p) for p in (range(n) if points is None else points))
        if len(self.points) != n or len(set(self.points)) != n:
            raise ValueError(f"points must name each of the {n} degrees of freedom once, got {points!r}.")
        self.point_matrix = np.eye(n)
        self.coupled = np.ones(n, dtype=bool)
        self.connections = tuple(connections)
        self._check_connections()

    @classmethod
    def from_modes(cls, frequencies, damping_ratios, mode_shapes, *, points, connections=(), coupled=None):
        """A structure given by its modes at the points that matter.

        Parameters
        ----------
        frequencies : array-like of shape (n_modes,)
            Natural frequencies, Hz (> 0).
        damping_ratios : array-like of shape (n_modes,)
            Viscous damping ratios (>= 0).
        mode_shapes : array-like of shape (n_points, n_modes)
            Mass-normalised mode shapes at ``points``: point ``p``'s
            displacement is ``mode_shapes[p] @ q`` for modal coordinates ``q``.
        points : sequence of str
        connections : sequence of Connection, default=()
        coupled : array-like of bool of shape (n_modes,), default=None
            Which modes the connections act on (None: all). A residual
            mode, which stands for the modes outside a fitted band as the
            driving point sees them, has no shape at a connection's points:
            forces enter it at the inputs only.

        Returns
        -------
        structure : Structure
            Its degrees of freedom are the modal coordinates.

        Examples
        --------
        >>> import numpy as np
        >>> from sklearn_pnlss.physics import Structure
        >>> s = Structure.from_modes([5.0, 12.0], [0.02, 0.01], [[0.5, 0.4], [0.6, -0.3]],
        ...                          points=["wing", "payload"])
        >>> np.round(np.sqrt(np.diag(s.stiffness)) / (2 * np.pi), 6)
        array([ 5., 12.])
        """
        f = np.atleast_1d(np.asarray(frequencies, dtype=np.float64))
        zeta = np.atleast_1d(np.asarray(damping_ratios, dtype=np.float64))
        shapes = np.atleast_2d(np.asarray(mode_shapes, dtype=np.float64))
        if f.ndim != 1 or not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise ValueError(f"frequencies must be positive finite numbers, got {frequencies!r}.")
        if zeta.shape != f.shape or not np.all(np.isfinite(zeta)) or np.any(zeta < 0):
            raise ValueError(f"damping_ratios must be {f.size} non-negative numbers, got {damping_ratios!r}.")
        points = [str(p) for p in points]
        if shapes.shape != (len(points), f.size) or not np.all(np.isfinite(shapes)):
            raise ValueError(f"mode_shapes must be finite, of shape (n_points, n_modes) = "
                             f"({len(points)}, {f.size}), got {np.shape(mode_shapes)}.")
        if len(set(points)) != len(points):
            raise ValueError(f"points must be distinct names, got {points!r}.")
        omega = 2 * np.pi * f
        out = cls.__new__(cls)
        out.mass = np.eye(f.size)
        out.damping = np.diag(2 * zeta * omega)
        out.stiffness = np.diag(omega**2)
        out.points = tuple(points)
        out.point_matrix = shapes
        out.coupled = np.ones(f.size, dtype=bool) if coupled is None else np.asarray(coupled, dtype=bool)
        if out.coupled.shape != f.shape:
            raise ValueError(f"coupled must hold one bool per mode ({f.size}), got {coupled!r}.")
        out.connections = tuple(connections)
        out._check_connections()
        return out

    def _check_connections(self):
        for i, c in enumerate(self.connections):
            if not isinstance(c, Connection):
                raise TypeError(f"connections[{i}] must be a Connection, got {c!r}.")
            for p in (c.point, c.other):
                if p is not None and p not in self.points:
                    raise ValueError(f"connections[{i}] names the point {p!r}, which is not one of {self.points}.")
        self._packed = pack_forces([c.element for c in self.connections])
        self._directions = np.zeros((self.n_dof, len(self.connections)))
        for i, c in enumerate(self.connections):
            self._directions[:, i] = self.direction(c.point, c.other)

    def __repr__(self):
        return f"Structure(n_dof={self.n_dof}, points={self.points!r}, connections={self.connections!r})"

    def with_connections(self, connections=(), *, springs=()):
        """A copy with more connections and linear springs and dampers.

        Parameters
        ----------
        connections : sequence of Connection, default=()
            Added to the structure's own.
        springs : sequence of (str, str or None, float, float), default=()
            ``(point, other, stiffness, damping)``: a linear spring (N/m) and
            damper (N s/m) on the relative motion of two points (``other``
            None: the ground), added to the matrices (a stiffness change
            where the structure joins, negative ones included).

        Returns
        -------
        structure : Structure

        Examples
        --------
        >>> import numpy as np
        >>> from sklearn_pnlss.physics import Structure
        >>> s = Structure(np.eye(2), np.zeros((2, 2)), np.diag([1.0, 2.0]), points=["a", "b"])
        >>> s.with_connections(springs=[("a", "b", 0.5, 0.0)]).stiffness
        array([[ 1.5, -0.5],
               [-0.5,  2.5]])
        """
        out = Structure.__new__(Structure)
        out.mass, out.points, out.point_matrix, out.coupled = self.mass, self.points, self.point_matrix, self.coupled
        out.damping, out.stiffness = self.damping.copy(), self.stiffness.copy()
        for i, (point, other, k, c) in enumerate(springs):
            for p in (point, other):
                if p is not None and p not in self.points:
                    raise ValueError(f"springs[{i}] names the point {p!r}, which is not one of {self.points}.")
            d = self.direction(point, other)
            out.stiffness += float(k) * np.outer(d, d)
            out.damping += float(c) * np.outer(d, d)
        out.connections = self.connections + tuple(connections)
        out._check_connections()
        return out

    @property
    def n_dof(self):
        """Number of degrees of freedom (modes for a modal structure)."""
        return self.mass.shape[0]

    @property
    def n_internal_states(self):
        """Internal states of the connections' elements."""
        return int(self._packed[3][-1])

    def _row(self, point):
        return self.point_matrix[self.points.index(point)]

    def direction(self, point, other=None):
        """The degrees of freedom's share of the relative motion of two
        points (``other`` None: the ground) that a connection between them
        acts on: ``phi_point - phi_other`` on the coupled modes."""
        return (self._row(point) - (0.0 if other is None else self._row(other))) * self.coupled

    def connection_response(self, freqs, point, other, *, sensors):
        """The sensors' response to a unit pair of forces between two points
        (``+1`` at ``point``, ``-1`` at ``other``; None: the ground), as a
        connection there exerts them, connections left out.

        Returns
        -------
        H : ndarray of shape (n_freqs, n_sensors), complex
        """
        return self._response(freqs, self.direction(point, other)[:, None], sensors)[:, :, 0]

    def dof_response(self, freqs, *, sensors):
        """The sensors' response to a unit force on each degree of freedom a
        connection acts on (a coupled mode, or a mass), connections left
        out: the columns a connection's force is spread over when its share
        of each is not taken from the point matrix.

        Returns
        -------
        H : ndarray of shape (n_freqs, n_sensors, n_coupled), complex
        """
        return self._response(freqs, np.eye(self.n_dof)[:, self.coupled], sensors)

    def _input_matrix(self, inputs):
        inputs = [inputs] if isinstance(inputs, str) else list(inputs)
        for p in inputs:
            if p not in self.points:
                raise ValueError(f"inputs names the point {p!r}, which is not one of {self.points}.")
        return np.stack([self._row(p) for p in inputs], axis=1), len(inputs)

    def frequency_response(self, freqs, *, inputs, sensors):
        """The linear structure's frequency response (connections left out).

        Parameters
        ----------
        freqs : array-like of shape (n_freqs,)
            Frequencies, Hz.
        inputs : sequence of str
            Points where the forces enter.
        sensors : sequence of (str, str)
            ``(point, kind)``, ``kind`` one of :data:`SENSOR_KINDS`.

        Returns
        -------
        H : ndarray of shape (n_freqs, n_sensors, n_inputs), complex
        """
        return self._response(freqs, self._input_matrix(inputs)[0], sensors)

    def _response(self, freqs, forces, sensors):
        """The sensors' response to the forces ``forces`` (n_dof, n_forces)
        on the degrees of freedom: (n_freqs, n_sensors, n_forces)."""
        rows, powers = self._sensor_rows(sensors)
        s = 2j * np.pi * np.atleast_1d(np.asarray(freqs, dtype=np.float64))[:, None, None]
        # one batched solve for every line (a model update evaluates it
        # hundreds of times)
        q = np.linalg.solve(s * s * self.mass + s * self.damping + self.stiffness,
                            np.broadcast_to(forces, (s.shape[0],) + forces.shape))
        return (rows[None] * s ** powers[None, :, None]) @ q

    def _sensor_rows(self, sensors):
        rows, powers = [], []
        for i, sensor in enumerate(sensors):
            if not (isinstance(sensor, (tuple, list)) and len(sensor) == 2):
                raise ValueError(f"sensors[{i}] must be a (point, kind) pair, got {sensor!r}.")
            point, kind = sensor
            if point not in self.points:
                raise ValueError(f"sensors[{i}] names the point {point!r}, which is not one of {self.points}.")
            if kind not in SENSOR_KINDS:
                raise ValueError(f"sensors[{i}] measures {kind!r}; use one of {SENSOR_KINDS}.")
            rows.append(self._row(point))
            powers.append(SENSOR_KINDS.index(kind))
        return np.array(rows).reshape(len(rows), self.n_dof), np.array(powers)

    def measure(self, sim, sensors):
        """The sensors' records of a :class:`StructureSimulation`.

        Returns
        -------
        records : ndarray of shape (n_samples, n_sensors)
        """
        rows, powers = self._sensor_rows(sensors)
        motion = (sim.y, sim.yd, sim.ydd)
        return np.stack([motion[k] @ row for row, k in zip(rows, powers)], axis=1)

    def _step_matrices(self, h, p_mat):
        """The linear step's matrices for step length ``h``, and the inverse
        mass a start's acceleration is solved with (see
        :func:`~sklearn_pnlss.physics._structure_run.structure_run`); made
        once per simulation, not per period."""
        c_acc, c_vel = 4.0 / h**2, 2.0 / h
        m, c, k, d = self.mass, self.damping, self.stiffness, self._directions
        k_eff = c_acc * m + c_vel * c + k
        solve = lambda b: np.linalg.solve(k_eff, b)  # noqa: E731
        w = solve(d)
        return dict(a_u=solve(p_mat), a_y=solve(c_acc * m + c_vel * c), a_yd=solve(c_acc * h * m + c),
                    a_ydd=solve(m), w=w, g_mat=d.T @ w, m_inv=np.linalg.inv(m))

    def _positions(self):
        n, nz = self.n_dof, self.n_internal_states
        return np.r_[0:2 * n, 3 * n:3 * n + nz]

    def simulate_fine(self, u_fine, *, fs, inputs, periodic=False, tol=1e-9, max_periods=50,
                      initial_state=None, warn=True, max_abs=None):
        """Simulate at the integration rate.

        Parameters
        ----------
        u_fine : array-like of shape (n_samples,) or (n_samples, n_inputs)
            Forces at ``inputs``, at rate ``fs`` (one period when ``periodic``).
        fs : float
            Integration rate, Hz.
        inputs : str or sequence of str
            The points the forces act on, one per column of ``u_fine``.
        periodic : bool, default=False
            True: the periodic steady state (period after period, with
            Newton steps on the period map, until a period ends within
            ``tol`` of its start, relative to each position's peak).
        tol : float, default=1e-9
        max_periods : int, default=50
        initial_state : ndarray, default=None
            A ``final_state`` to start from (default: rest).
        warn : bool, default=True
            Warn when the steady state is not reached.
        max_abs : float, default=None
            A bound on every point's displacement, checked after each
            period: FloatingPointError once it is exceeded (a trial point
            that runs away stops at once, not after its last period).

        Returns
        -------
        StructureSimulation
        """
        u, h, p_mat, mats = self._prepared(u_fine, fs, inputs)
        n, n_dof, nz = u.shape[0], self.n_dof, self.n_internal_states
        state = self._start_state(initial_state)

        def run(state, init, n_steps):
            out = self._integrate(u, h, p_mat, mats, state, init, n_steps, n)
            return out[:5]

        if not periodic:
            y, yd, ydd, z, failed = run(state, True, n - 1)
            return StructureSimulation(y, yd, ydd, z, 1.0 / h, 1, failed, state)
        if isinstance(max_periods, bool) or not isinstance(max_periods, Integral) or max_periods < 1:
            raise ValueError(f"max_periods must be a positive int, got {max_periods!r}.")
        idx = self._positions()

        def period_jacobian(start, idx):
            # the positions' derivatives over a period, from the integrator's
            # sensitivities along each start position (its acceleration and
            # rates recomputed, as a shot starts)
            tangents = np.zeros((idx.size, start.size))
            tangents[np.arange(idx.size), idx] = 1.0
            self._integrate(u, h, p_mat, mats, start.copy(), True, n, 0, tangents, np.full(idx.size, -1), [])
            return tangents[:, idx].T

        shooter = PeriodShooter(lambda st, ini: run(st, ini, n)[:2], state.size, nz, period_jacobian, positions=idx)
        init, period, total_failed, converged, plain = True, 0, 0, False, []
        while period < max_periods:
            start = state.copy()
            y, yd, ydd, z, failed = run(state, init, n)
            if max_abs is not None:  # the points' motion only where it is bounded
                _check_bound(y @ self.point_matrix.T, max_abs)
            init, period, total_failed = False, period + 1, total_failed + failed
            traces = [y[:, j] for j in range(n_dof)] + [yd[:, j] for j in range(n_dof)] + [z[:, j] for j in range(nz)]
            scale = np.array([max(np.max(np.abs(t)), 1e-300) for t in traces])
            change = float(np.max(np.abs(state[idx] - start[idx]) / scale))
            if period > 1 and change <= tol:
                converged = True
                break
            if not shooter.active:
                plain.append(change)
                if _futile(plain, tol, max_periods - period):
                    break
            if period >= _SHOOT_AFTER and period < max_periods:
                shot, used = shooter.step(start, state, traces, max_periods - period - 1)
                period += used
                if shot is not None:
                    state, init = shot, True
        if not converged and warn:
            warnings.warn(f"periodic steady state not reached within max_periods={max_periods} periods "
                          f"(tolerance {tol:g}); the last period is returned.", ConvergenceWarning, stacklevel=2)
        return StructureSimulation(y, yd, ydd, z, 1.0 / h, period, total_failed, state)

    def _prepared(self, u_fine, fs, inputs):
        """The input as rows of forces, the step length, the input matrix
        and the linear step's matrices."""
        p_mat, n_in = self._input_matrix(inputs)
        u = np.asarray(u_fine, dtype=np.float64)
        u = u.reshape(-1, 1) if u.ndim == 1 else u
        if u.ndim != 2 or u.shape[1] != n_in or u.shape[0] < 2:
            raise ValueError(f"u_fine must have one column per input point ({n_in}) and at least 2 samples, "
                             f"got shape {np.shape(u_fine)}.")
        if not np.all(np.isfinite(u)):
            raise ValueError("u_fine contains NaN or infinite values.")
        h = 1.0 / _positive_real("fs", fs)
        return np.ascontiguousarray(u), h, p_mat, self._step_matrices(h, p_mat)

    def _start_state(self, initial_state):
        state = np.zeros(3 * self.n_dof + 2 * self.n_internal_states)
        if initial_state is None:
            return state
        initial_state = np.asarray(initial_state, dtype=np.float64)
        if initial_state.shape != state.shape or not np.all(np.isfinite(initial_state)):
            raise ValueError(f"initial_state must be a finite final_state of this structure "
                             f"(shape {state.shape}), got shape {initial_state.shape}.")
        return initial_state.copy()

    def _integrate(self, u, h, p_mat, mats, state, init, n_steps, n_out, tangents=None, param_of=None,
                   sensors=None):
        """One run of the kernel; with ``tangents``, also the sensors'
        derivatives along them."""
        n_dof, nz = self.n_dof, self.n_internal_states
        y, yd, ydd = (np.empty((n_out, n_dof)) for _ in range(3))
        z = np.empty((n_out, nz))
        kinds, p_off, params, z_off, _ = self._packed
        if tangents is None:
            tangents, param_of = np.zeros((0, state.size)), np.zeros(0, dtype=np.int64)
            rows, kind, sens = np.zeros((0, n_dof)), np.zeros(0, dtype=np.int64), np.zeros((0, 0, 0))
        else:
            rows, kind = self._sensor_rows(sensors)
            sens = np.empty((n_out, rows.shape[0], tangents.shape[0]))
        failed = structure_run(u, n_steps, h, mats["a_u"], mats["a_y"], mats["a_yd"], mats["a_ydd"], mats["w"],
                               mats["g_mat"], self._directions, p_mat, self.damping, self.stiffness,
                               mats["m_inv"], kinds, p_off, params, z_off, state, init, y, yd, ydd, z,
                               _NEWTON_RTOL, _NEWTON_MAX_ITER, tangents, param_of.astype(np.int64),
                               np.ascontiguousarray(rows), kind.astype(np.int64), sens)
        if not (np.all(np.isfinite(state)) and np.all(np.isfinite(tangents))):
            raise FloatingPointError("the simulation diverged (non-finite state).")
        return y, yd, ydd, z, failed, sens

    @property
    def parameter_vector(self):
        """The connections' elements' parameters, in the order of
        ``connections`` (each element's ``param_names``): what
        :meth:`sensitivity` differentiates by."""
        return self._packed[2].copy()

    def sensitivity(self, u_fine, *, fs, inputs, sensors, periodic=False, steady_state=None):
        """The sensors' records and their exact derivatives by
        :attr:`parameter_vector`.

        The derivatives are those of the integration scheme itself (each
        converged step's equations differentiated, one run for all
        parameters). A periodic steady state moves with the parameters too:
        the period is run once more with the start state's directions, and
        the orbit's own derivative solved from the period map.

        Parameters
        ----------
        u_fine : array-like of shape (n_samples,) or (n_samples, n_inputs)
        fs : float
            Integration rate, Hz.
        inputs : str or sequence of str
        sensors : sequence of (str, str)
        periodic : bool, default=False
            True: ``u_fine`` is one period and ``steady_state`` the
            ``final_state`` of a periodic :meth:`simulate_fine` of it.
        steady_state : ndarray, default=None

        Returns
        -------
        records : ndarray of shape (n_samples, n_sensors)
        derivatives : ndarray of shape (n_samples, n_sensors, n_parameters)
        """
        u, h, p_mat, mats = self._prepared(u_fine, fs, inputs)
        n, n_params = u.shape[0], self._packed[2].size
        state = self._start_state(None)
        if not periodic:
            tangents = np.zeros((n_params, state.size))
            y, yd, ydd, z, _, sens = self._integrate(u, h, p_mat, mats, state, True, n - 1, n, tangents,
                                                     np.arange(n_params), sensors)
            return self.measure(StructureSimulation(y, yd, ydd, z, 1 / h, 1, 0, state), sensors), sens
        if steady_state is None:
            raise ValueError("a periodic sensitivity needs the steady_state of a converged periodic simulate_fine.")
        state = self._start_state(steady_state)
        n_state = state.size
        # directions: each of the start state's (the period map), then each
        # parameter's from the same start
        tangents = np.zeros((n_state + n_params, n_state))
        tangents[:n_state] = np.eye(n_state)
        param_of = np.r_[np.full(n_state, -1), np.arange(n_params)]
        y, yd, ydd, z, _, sens = self._integrate(u, h, p_mat, mats, state, False, n, n, tangents, param_of, sensors)
        phi, b = tangents[:n_state].T, tangents[n_state:].T
        start = np.linalg.solve(np.eye(n_state) - phi, b)
        records = self.measure(StructureSimulation(y, yd, ydd, z, 1 / h, 1, 0, state), sensors)
        return records, sens[:, :, n_state:] + sens[:, :, :n_state] @ start

    def simulate(self, u, *, fs, inputs, sensors, periodic=False, oversampling=5, decimation=(5,)):
        """The sensors' records at the data rate.

        The inputs are interpolated to ``oversampling * fs`` by FFT,
        integrated there and the sensors' records decimated by the FIR chain
        ``decimation``, as :meth:`Oscillator.simulate` does.

        Parameters
        ----------
        u : array-like of shape (n_samples,) or (n_samples, n_inputs)
            Forces at rate ``fs`` (one period when ``periodic``).
        fs : float
        inputs : str or sequence of str
        sensors : sequence of (str, str)
            ``(point, kind)``, ``kind`` one of :data:`SENSOR_KINDS`.
        periodic : bool, default=False
        oversampling : int, default=5
        decimation : sequence of int, default=(5,)
            Its product must equal ``oversampling``.

        Returns
        -------
        records : ndarray of shape (n_samples, n_sensors)
        """
        u = np.asarray(u, dtype=np.float64)
        columns = [u] if u.ndim == 1 else [u[:, j] for j in range(u.shape[1])]
        if not isinstance(oversampling, Integral) or oversampling < 1 or int(np.prod(decimation)) != oversampling:
            raise ValueError(f"oversampling must be a positive int equal to the product of decimation "
                             f"{tuple(decimation)}, got {oversampling!r}.")
        u_fine = np.stack([upsample_fft(check_signal(c, "u"), oversampling, periodic=periodic) for c in columns],
                          axis=1)
        sim = self.simulate_fine(u_fine, fs=fs * oversampling, inputs=inputs, periodic=periodic)
        if sim.n_newton_failures:
            warnings.warn(f"Newton-Raphson did not fully converge in {sim.n_newton_failures} integration steps.",
                          ConvergenceWarning, stacklevel=2)
        return decimate_columns(self.measure(sim, sensors), decimation, periodic=periodic)

