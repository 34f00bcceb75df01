"""What every nonlinear state-space model of the library shares.

A model is a linear part plus a static nonlinearity, with its parameters in
named blocks. Subclasses say which blocks (``_block_names``, in theta order)
and provide two compiled kernels through ``_run(U, x0)`` (simulation:
``(Y, X, n_ok, x_end)``) and ``_sensitivity(U, x, Sx, n_skip, J)`` (the
exact Jacobian of the output by the sensitivity recursion, from the state
``x`` and its sensitivity ``Sx``, both advanced in place). Simulation of signals
from rest or in periodic steady state, the training residual and Jacobian
are written here once.
"""
from dataclasses import dataclass, fields, replace

import numpy as np

from ..utils.threads import over_column_spans
from ..utils.validation import is_periodic

# DivergenceError is documented where users import it: sklearn_pnlss.DivergenceError.
__all__ = ["Segment", "StateSpaceModel", "unbounded"]

# Periods simulated at most in search of a periodic steady state.
MAX_STEADY_PERIODS = 200

# How far past its trusted range (in range widths) a simulation may take the
# nonlinearity's variables before the model counts as running away.
RUNAWAY_FACTOR = 1.0

# The records new inputs are dealt to and each simulated in turn (see
# StateSpaceModel.runaways_in_turn): a PNLSS model simulates them side by
# side, one sample of all of them at a time, in loops the compiler
# vectorises over the records (two vectors of four on this machine).
CHECK_RECORDS = 8

# The fewest samples of records given a thread: some milliseconds of a small
# model's simulation, against tens of microseconds to hand them over.
RECORD_PART_SAMPLES = 50_000


def unbounded(k):
    """Bounds ``[-inf, inf]`` for ``k`` variables: no trusted range."""
    return np.tile([-np.inf, np.inf], (k, 1))


class DivergenceError(ValueError):
    """The model's simulation left any reasonable range (at sample
    ``sample`` of the simulated signal, when known)."""

    def __init__(self, message, sample=None):
        super().__init__(message)
        self.sample = sample


@dataclass
class Segment:
    """One training signal ready for simulation: ``U`` is simulated from rest
    and the first ``n_skip`` samples (a transient) are left out of the cost;
    or, with ``init_window`` (and ``n_skip`` zero), from the state whose
    simulation best reproduces the first ``init_window`` samples of ``Y``
    (a record that does not start from rest), all samples in the cost.

    Optional weighting of the squared error (see
    :mod:`sklearn_pnlss.statespace.objective`): ``time_weight`` of the shape
    of ``Y``, or ``freq_weight`` of shape (period // 2 + 1, p) per DFT bin of
    each ``period``-sample block of ``Y``.
    """

    U: np.ndarray
    Y: np.ndarray  # target for U[n_skip:]
    n_skip: int
    time_weight: np.ndarray | None = None
    freq_weight: np.ndarray | None = None
    period: int | None = None
    init_window: int = 0


class StateSpaceModel:
    """Mixin for dataclass models with matrices ``A, B, C, D``, parameter
    blocks named by ``_block_names`` and ``bounds`` (k, 2): the trusted range
    of the ``k`` variables its nonlinearity is evaluated at
    (``bounded_variables``), outside which the nonlinearity is continued
    (held at the edge, by default)."""

    _block_names: tuple = ()

    @property
    def n_states(self):
        return self.A.shape[0]

    @property
    def blocks(self):
        return tuple(getattr(self, name) for name in self._block_names)

    @property
    def theta(self):
        return np.concatenate([M.ravel() for M in self.blocks])

    @property
    def n_params(self):
        return sum(M.size for M in self.blocks)

    @property
    def n_fixed_params(self):
        """Entries of the parameter vector that no step moves (see
        :meth:`step_basis`); not counted as the model's parameters."""
        return 0

    @property
    def n_null_directions(self):
        """Parameter directions that leave the output unchanged (dropped
        from each Levenberg-Marquardt step): the n^2 of the state basis."""
        return self.n_states**2

    def state_matrix_at_rest(self):
        """The state equation's Jacobian in ``x`` at rest (``x = 0``,
        ``u = 0``): ``A`` plus whatever linear term the nonlinearity has
        there. Its spectral radius says whether the model, left alone,
        returns to rest: a passive structure does, a model with a radius
        above 1 oscillates by itself below the amplitudes it was fitted at."""
        return self.A

    def radius_at_rest(self):
        """The spectral radius of :meth:`state_matrix_at_rest`."""
        return float(np.max(np.abs(np.linalg.eigvals(self.state_matrix_at_rest())), initial=0.0))

    def stable_at_rest(self):
        """Whether :meth:`radius_at_rest` is below 1."""
        return self.radius_at_rest() < 1.0

    def step_basis(self, states_inputs):
        """Basis in which Levenberg-Marquardt solves its steps (see
        :func:`~sklearn_pnlss.statespace.levenberg_marquardt.levenberg_marquardt`),
        given the points ``states_inputs`` (rows ``[x; u]``) the model
        operates at; None: the parameters themselves."""
        return None

    def with_theta(self, theta):
        """A copy with the parameters ``theta`` (in block order)."""
        new, i = {}, 0
        for name, M in zip(self._block_names, self.blocks):
            new[name] = np.asarray(theta[i : i + M.size]).reshape(M.shape).copy()
            i += M.size
        return replace(self, **new)

    def rescaled(self, state_scale, input_scale, output_scale):
        """The same model in the units where ``x = state_scale * x_n``,
        ``u = input_scale * u_n`` and ``y = output_scale * y_n`` (this
        model's variables being ``x_n, u_n, y_n``): it simulates the same
        signals, rescaled."""
        T, Ti = np.diag(state_scale), np.diag(1 / state_scale)
        Su_i, Sy = np.diag(1 / input_scale), np.diag(output_scale)
        return replace(
            self, A=T @ self.A @ Ti, B=T @ self.B @ Su_i, C=Sy @ self.C @ Ti, D=Sy @ self.D @ Su_i,
            **self._rescaled_nonlinearity(state_scale, input_scale, output_scale),
        )

    def _bounds(self):
        return np.ascontiguousarray(self.bounds[:, 0]), np.ascontiguousarray(self.bounds[:, 1])

    def with_trusted_range(self, states_inputs, margin=0.0):
        """A copy whose ``bounds`` are the range of its nonlinearity's
        variables at the points ``states_inputs`` (rows ``[x; u]``, e.g. a
        simulation of the training inputs), widened by ``margin`` times the
        range's width on each side."""
        v = self._variables_by_row(states_inputs)
        lo, hi = v.min(axis=1), v.max(axis=1)
        pad = margin * (hi - lo)
        return replace(self, bounds=np.column_stack([lo - pad, hi + pad]))

    def _variables_by_row(self, states_inputs):
        """:meth:`bounded_variables` at the points ``states_inputs``, a
        variable a row (contiguous): numpy reduces a few long rows ten to
        thirty times faster than the columns of a tall array (16,384 points
        of three variables: 0.03 against 0.85 ms for their minima and
        maxima)."""
        return np.ascontiguousarray(self.bounded_variables(np.asarray(states_inputs, dtype=float)).T)

    def without_bounds(self):
        """A copy with the plain polynomial nonlinearity (no trusted range)."""
        return replace(self, bounds=unbounded(self.bounds.shape[0]))

    def copy(self):
        # None (an optional block left out) stays None
        return replace(self, **{f.name: np.copy(v) for f in fields(self) if (v := getattr(self, f.name)) is not None})

    def _checked_run(self, U, x0=None):
        """Outputs, states and final state from ``x0`` (zero by default);
        raises :class:`DivergenceError` when the state leaves the range."""
        x0 = np.zeros(self.n_states) if x0 is None else x0
        Y, X, n_ok, x_end = self._run(np.ascontiguousarray(U), x0)
        if n_ok < U.shape[0]:
            raise DivergenceError(f"the simulation diverges at sample {n_ok}", sample=n_ok)
        return Y, X, x_end

    def simulate(self, U, x0=None):
        """Output and final state from ``x0`` (zero by default); raises
        :class:`DivergenceError` when the state leaves the range."""
        Y, _, x_end = self._checked_run(U, x0)
        return Y, x_end

    def simulate_states(self, U, x0=None):
        """States (N, n) along the simulation from ``x0``."""
        return self._checked_run(U, x0)[1]

    def steady_state_start(self, U_period, max_periods=MAX_STEADY_PERIODS, rtol=1e-10):
        """State at the start of a period once the response is periodic:
        period after period from rest until the state repeats."""
        return self._steady_period(U_period, max_periods, rtol)[0]

    def _steady_period(self, U_period, max_periods=MAX_STEADY_PERIODS, rtol=1e-10):
        """``(x, Y, X)``: the state at the start of a period once the
        response is periodic (period after period from rest until the state
        repeats), and the outputs and states of the last period simulated,
        which started within ``rtol`` of it: the steady-state period itself,
        so that callers need not simulate it once more (None, None when the
        state has not repeated within ``max_periods``)."""
        U_period = np.ascontiguousarray(U_period)
        x = np.zeros(self.n_states)
        for _ in range(max_periods):
            Y, X, x_new = self._checked_run(U_period, x)
            if np.linalg.norm(x_new - x) <= rtol * (1.0 + np.linalg.norm(x_new)):
                return x_new, Y, X
            x = x_new
        return x, None, None

    def _steady_run(self, U, period, max_periods=MAX_STEADY_PERIODS):
        """Outputs and states of ``U`` in periodic steady state: the
        converged period repeated when ``U`` repeats it, else a simulation
        of ``U`` from the steady-state start (from where ``max_periods``
        left it when the state has not repeated)."""
        x0, Y, X = self._steady_period(U[:period], max_periods)
        k = U.shape[0] // period
        if Y is not None and (k == 1 or np.array_equal(U.reshape(k, period, -1), np.broadcast_to(
                U[:period], (k, period, U.shape[1])))):
            return np.tile(Y, (k, 1)), np.tile(X, (k, 1))
        return self._checked_run(U, x0)[:2]

    def simulate_signal(self, U, period=None):
        """Simulate one signal; periodic steady state when ``period`` is
        given (the length is a multiple of it), else from rest."""
        if period is None:
            return self.simulate(U)[0]
        return self._steady_run(U, period)[0]

    def states_inputs(self, U, period=None, max_periods=MAX_STEADY_PERIODS):
        """``[x; u]`` (N, n + m) along the simulation of one signal ``U``:
        in periodic steady state when its length is a whole number of
        ``period`` samples (sought over at most ``max_periods``), else from
        rest. Raises :class:`DivergenceError`."""
        X = self._steady_run(U, period, max_periods)[1] if is_periodic(U.shape[0], period) else self.simulate_states(U)
        return np.hstack([X, U])

    def trajectory(self, U_list, period=None):
        """:meth:`states_inputs` of each signal of ``U_list``, stacked: the
        region the model operates in on those inputs."""
        return np.vstack([self.states_inputs(U, period) for U in U_list])

    def segments_trajectory(self, segments):
        """``[x; u]`` along each training segment's simulation from the state
        the cost starts it from (:meth:`segment_start`), stacked: the region
        the fitted model operates in. From rest instead, a model can diverge
        that the cost never saw diverge (EMPS's increments, a spline branch
        whose edge slope pulls outwards: at sample 7,759 of 24,841)."""
        return np.vstack([np.hstack([self.simulate_states(seg.U, self.segment_start(seg)), seg.U])
                          for seg in segments])

    def range_excursion(self, U, period=None, max_periods=MAX_STEADY_PERIODS):
        """How far the simulation of ``U`` (periodic steady state with
        ``period``, sought over at most ``max_periods``) takes the
        nonlinearity's variables past their trusted range: the largest
        excursion as a fraction of the range's width (0 inside it or without
        bounds, inf when the simulation diverges)."""
        try:
            return self._excursion(self.states_inputs(U, period, max_periods))
        except DivergenceError:
            return np.inf

    def simulate_with_excursion(self, U):
        """``(Y, excursion)``: the output of ``U`` simulated from rest and
        :meth:`range_excursion` along that simulation, from the one run
        (``(None, inf)`` when it diverges): a check record is checked for
        both."""
        try:
            Y, X, _ = self._checked_run(U)
        except DivergenceError:
            return None, np.inf
        return Y, self._excursion(np.hstack([X, U]))

    def _excursion(self, states_inputs):
        """:meth:`range_excursion` along the rows ``[x; u]`` given."""
        v = self._variables_by_row(states_inputs)
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        with np.errstate(invalid="ignore"):  # inf / inf without bounds
            excess = np.maximum(lo - v.min(axis=1), v.max(axis=1) - hi) / (hi - lo)
        excess = excess[np.isfinite(hi - lo)]
        return float(max(excess.max(), 0.0)) if excess.size else 0.0

    def runaways_in_turn(self, inputs, factor=RUNAWAY_FACTOR, stop_at_first=False):
        """The places in ``inputs`` (of one length) the model runs away on
        (see :meth:`runs_away`), each simulated from the state the input
        before it in its record left: the inputs are dealt to
        :data:`CHECK_RECORDS` records (input ``i`` to record ``i %
        CHECK_RECORDS``), each simulated in turn from rest, and from rest
        again after an input it ran away on (so that one runaway is not
        counted on the inputs after it). With ``stop_at_first``, the
        simulation stops at the first runaway (a verdict, not a count).

        New realisations of a periodic excitation so checked cost a period
        each, where seeking each one's steady state costs two at least; the
        switch between two realisations is a transient, as in a
        measurement, and a slow drift away is followed over a record. The
        records are simulated side by side, in threads when long enough
        (:data:`RECORD_PART_SAMPLES`), and by a PNLSS model in one
        vectorised kernel."""
        if not len(inputs):
            return np.array([], dtype=int)
        U = np.ascontiguousarray(np.stack(inputs), dtype=float)
        excursions = np.full(len(U), np.nan)
        record_samples = U.shape[1] * -(-len(U) // CHECK_RECORDS)
        over_column_spans(
            lambda r0, r1: self._excursions_in_turn(U, CHECK_RECORDS, r0, r1, factor, stop_at_first, excursions),
            CHECK_RECORDS, self._records_a_thread(record_samples))
        return np.flatnonzero(excursions > factor)

    def _records_a_thread(self, record_samples):
        """The fewest check records of ``record_samples`` samples worth a
        thread of their own (see :data:`RECORD_PART_SAMPLES`)."""
        return -(-RECORD_PART_SAMPLES // record_samples)

    def _excursions_in_turn(self, U, n_records, r0, r1, factor, stop_at_first, out):
        """The excursions of :meth:`runaways_in_turn` (``out[i]`` for input
        ``U[i]``, NaN where not simulated), records ``r0`` to ``r1 - 1``
        only: one input at a time here."""
        for r in range(r0, r1):
            x = np.zeros(self.n_states)
            for i in range(r, len(U), n_records):
                _, X, n_ok, x_end = self._run(U[i], x)
                out[i] = np.inf if n_ok < U.shape[1] else self._excursion(np.hstack([X, U[i]]))
                if out[i] > factor and stop_at_first:
                    return
                x = np.zeros(self.n_states) if out[i] > factor else x_end

    def runs_away(self, U, period=None, factor=RUNAWAY_FACTOR, max_periods=MAX_STEADY_PERIODS):
        """Whether the simulation of ``U`` diverges, or takes the
        nonlinearity's variables past their trusted range by more than
        ``factor`` times its width: a bounded model then sits on an orbit it
        was never fitted for. ``max_periods``: see :meth:`range_excursion`
        (an orbit that runs away seldom becomes periodic, so it always
        takes that many)."""
        return self.range_excursion(U, period, max_periods) > factor

    def settles(self, U_period, max_periods=MAX_STEADY_PERIODS, rtol=1e-10):
        """Whether the response to ``U_period`` repeated from rest settles
        into a periodic steady state within ``max_periods`` periods (the
        state repeats to ``rtol``, as :meth:`simulate_signal` seeks it);
        False when it diverges.

        A response that contracts steadily is taken to settle as soon as
        its rate, the last three periods' largest ratio of successive state
        changes, brings the change below ``rtol`` within the periods left:
        a slow but steady approach need not be simulated to the end, while
        a model that oscillates by itself keeps changing at a rate near 1."""
        x = np.zeros(self.n_states)
        changes = []
        for k in range(max_periods):
            try:
                x_new = self._checked_run(U_period, x)[2]
            except DivergenceError:
                return False
            tolerance = rtol * (1.0 + np.linalg.norm(x_new))
            changes.append(np.linalg.norm(x_new - x))
            x = x_new
            if changes[-1] <= tolerance:
                return True
            if len(changes) >= 4:
                rate = max(b / a for a, b in zip(changes[-4:-1], changes[-3:]) if a > 0)
                if rate < 1.0 and changes[-1] * rate ** (max_periods - 1 - k) <= tolerance:
                    return True
        return False

    def segment_start(self, seg):
        """The state a segment's simulation starts from: rest, or the one
        its first ``init_window`` outputs show. The Jacobian takes it as
        given (its change with the parameters is left out: the state is
        re-read at every evaluation of the cost, a step at a time)."""
        if not seg.init_window:
            return np.zeros(self.n_states)
        from .initial_state import estimate_initial_state  # it simulates with this module's models

        return estimate_initial_state(self, seg.U, seg.Y[: seg.init_window])

    def segment_error(self, seg, start=None):
        """Simulation error (T, p) on one segment, or None when it diverges;
        ``start``: its :meth:`segment_start`, when already read."""
        run = self.segment_run(seg, start)
        return None if run is None else run[0]

    def segment_run(self, seg, start=None):
        """``(error, states)`` of one segment's simulation: the error (T, p)
        and the states along all of ``seg.U`` (as :meth:`segments_trajectory`
        reads them); None when it diverges."""
        start = self.segment_start(seg) if start is None else start
        Y, X, n_ok, _ = self._run(np.ascontiguousarray(seg.U), start)
        if n_ok < seg.U.shape[0]:
            return None
        return Y[seg.n_skip :] - seg.Y, X

    @property
    def n_state_params(self):
        """Parameters that move the state: the blocks before ``C`` (the
        sensitivity recursion carries their derivatives in time)."""
        names = self._block_names
        return sum(getattr(self, name).size for name in names[: names.index("C")])

    def segment_jacobian(self, seg):
        """Exact Jacobian (T, p, n_params) of :meth:`segment_error`."""
        J = np.empty((seg.U.shape[0] - seg.n_skip, self.C.shape[0], self.n_params))
        for _ in self.jacobian_blocks(seg, J.shape[0], out=J):
            pass
        return J

    def jacobian_blocks(self, seg, block_length, out=None, buffer=None, start=None, steady=None):
        """The rows of :meth:`segment_jacobian` ``block_length`` samples at a
        time: yields ``(start, J_block)``, ``J_block`` of shape (L, p,
        n_params) holding rows ``start:start + L`` of the segment's error.

        The sensitivity recursion runs once through the signal, carrying its
        state from block to block, so only one block is ever held. Each block
        is written into the same work array (``buffer``, of at least
        ``block_length`` rows, or one made here), valid until the next block
        is asked for; with ``out`` (the whole Jacobian, (T, p, n_params)),
        each block is written into its rows instead. On a long signal with
        many parameters this is the difference between a block of tens of
        megabytes and a Jacobian of gigabytes, whose first touch alone cost
        more than its arithmetic (F-16, 2,893 parameters: 1.5 s of 2.3 s per
        8,192-sample segment); a ``buffer`` reused from segment to segment
        spares even the block's. ``start``: the segment's
        :meth:`segment_start`, when already read (reading it is a
        Gauss-Newton fit of its first samples).

        ``steady`` (a dict), on a periodic segment with a transient: the
        sensitivities of the periodic steady state, without running the
        recursion through the transient. The state is simulated through the
        transient alone; the recursion starts at the first scored sample
        from zero sensitivity, and carries n more columns, ``K = dy/dx0``
        (the blocks are then (L, p, n_params + n_states), those columns
        last, ``buffer`` and ``out`` sized to match). The sensitivity of the
        start state in steady state, ``S0``, is the fixed point of the
        periods, ``S0 = Phi S0 + R`` with ``Phi`` the state's own
        sensitivity over the segment and ``R`` the parameters' from zero;
        once the blocks are exhausted ``steady["S0"]`` holds it, and the
        Jacobian is ``J[..., :n_params] + K @ [S0, 0]``. Exact in steady
        state, and the transient (up to a period, on a lightly damped
        structure) costs a simulation instead of a sensitivity recursion.
        Other segments: ``steady`` is ignored and left empty.
        """
        U = np.ascontiguousarray(seg.U)
        T = U.shape[0] - seg.n_skip
        block_length = max(1, min(int(block_length), T))
        x = (self.segment_start(seg) if start is None else start).copy()
        n, n_sx = self.n_states, self.n_state_params
        extend = steady is not None and self.steady_state_segment(seg)
        n_cols = self.n_params + (n if extend else 0)
        if out is None and buffer is None:
            buffer = np.empty((block_length, self.C.shape[0], n_cols))
        if extend:
            Sx = np.zeros((n, n_sx + n))
            Sx[:, n_sx:] = np.eye(n)
            _, _, _, x = self._run(U[: seg.n_skip], x)
        else:
            Sx = np.zeros((n, n_sx))
            # The transient before the first row, then the blocks of rows.
            self._sensitivity(U[: seg.n_skip], x, Sx, seg.n_skip, (out if out is not None else buffer)[:0])
        for start in range(0, T, block_length):
            stop = min(start + block_length, T)
            J = out[start:stop] if out is not None else buffer[: stop - start]
            self._sensitivity(U[seg.n_skip + start : seg.n_skip + stop], x, Sx, 0, J)
            yield start, J
        if extend:
            R, Phi = Sx[:, :n_sx], Sx[:, n_sx:]
            try:
                steady["S0"] = np.linalg.solve(np.eye(n) - Phi, R)
            except np.linalg.LinAlgError:  # a pole at 1: no steady state; take the start as given
                steady["S0"] = np.zeros_like(R)

    @staticmethod
    def steady_state_segment(seg):
        """Whether ``seg`` is periodic steady state with a transient
        prepended: whole periods scored after it, and an input that repeats
        with the period throughout, transient included (an averaged period
        does; measured periods, each with its own noise, do not). Its
        Jacobian can then be taken in steady state (see
        :meth:`jacobian_blocks`)."""
        P = seg.period
        return (bool(P) and seg.n_skip > 0 and seg.Y.shape[0] % P == 0
                and np.array_equal(seg.U[P:], seg.U[:-P]))

    def steady_state_pays(self, seg):
        """Whether taking ``seg``'s Jacobian in steady state is the cheaper
        of the two exact ways: it spares the recursion through the
        transient (n_skip samples of n_state_params columns) and costs n
        start-state columns over the scored samples, twice over for their
        products and the fold. The F-16's levels (a transient of a whole
        period, 2,860 columns) gain half the recursion; the Bouc-Wen
        record (713 samples of transient before 8,192, 60 columns) would
        gain nothing and keeps the plain recursion."""
        T = seg.U.shape[0] - seg.n_skip
        return (self.steady_state_segment(seg)
                and seg.n_skip * self.n_state_params > 2 * T * self.n_states)

    def residual(self, segments):
        """Stacked unweighted simulation errors, or None when any segment
        diverges."""
        out = []
        for seg in segments:
            err = self.segment_error(seg)
            if err is None:
                return None
            out.append(err.ravel())
        return np.concatenate(out)

    def jacobian(self, segments):
        """Exact Jacobian of :meth:`residual`."""
        J = [self.segment_jacobian(seg) for seg in segments]
        return np.concatenate(J).reshape(-1, self.n_params)
