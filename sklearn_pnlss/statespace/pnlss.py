"""The polynomial nonlinear state-space model."""
from dataclasses import dataclass

import numpy as np

from ..utils.threads import over_column_spans
from ._pnlss_kernels import pnlss_excursions_in_turn, pnlss_jacobian, pnlss_simulate
from .model_base import CHECK_RECORDS, DivergenceError, Segment, StateSpaceModel, unbounded

__all__ = ["PNLSSModel", "Segment"]

# A thread of the Jacobian's recursion is given columns whose carrying
# ((n + p) n multiply-adds per column and sample) costs at least this many
# times the work it repeats: each thread simulates the state and forms its
# local linear map itself (per sample, each state derivative of a monomial:
# its factors and a column of n or p multiply-adds). The kernel alone gains
# from two spans far below this (8,192 samples, 2 cores: 1.22 times faster
# at a ratio of 9, 1.52 at 43), but inside a fit it follows the Gram
# matrix, whose BLAS threads go on spinning for a while: 10-iteration
# Bouc-Wen fits of 421 and 1,156 parameters ran 1.2 and 1.0 times as long
# split, the F-16's (ratio 43: two spans) 0.8 times.
SPAN_WORK_RATIO = 16


@dataclass
class PNLSSModel(StateSpaceModel):
    """x(t+1) = A x + B u + E zeta([x; u]), y = C x + D u + F eta([x; u]).

    ``exE`` / ``exF`` hold the monomial exponents over the variables
    ``[x; u]``. Parameter vector order: A, B, E, C, D, F (row-major): the
    blocks that move the state first, as the Jacobian kernel expects.

    ``bounds`` (n + m, 2), default None (no bounds): the trusted box of
    ``[x; u]``; the monomials are evaluated at ``[x; u]`` held inside it,
    so they stay bounded (a stable ``A`` then bounds the state for every
    bounded input). The linear terms are never held. A trusted range from
    data bounds the states only: the input is the user's, known and bounded,
    and holding the states already bounds every monomial of a bounded input.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    E: np.ndarray
    F: np.ndarray
    exE: np.ndarray
    exF: np.ndarray
    bounds: np.ndarray | None = None

    _block_names = ("A", "B", "E", "C", "D", "F")

    @property
    def n_nonlinear_params(self):
        """Coefficients of the monomials, ``E`` and ``F``."""
        return self.E.size + self.F.size

    def __post_init__(self):
        k = self.A.shape[0] + self.B.shape[1]
        self.bounds = unbounded(k) if self.bounds is None else np.array(self.bounds, dtype=float)
        if self.bounds.shape != (k, 2):
            raise ValueError(f"bounds must have shape {(k, 2)} (n_states + n_inputs, 2); got {self.bounds.shape}.")

    def with_trusted_range(self, states_inputs, margin=0.0):
        trusted = super().with_trusted_range(states_inputs, margin)
        trusted.bounds[self.A.shape[0] :] = [-np.inf, np.inf]
        return trusted

    with_trusted_range.__doc__ = StateSpaceModel.with_trusted_range.__doc__ + " The inputs stay unbounded."

    def state_matrix_at_rest(self):
        """``A`` plus the monomials of degree 1 in a state (the others
        vanish with their derivatives at rest)."""
        n = self.A.shape[0]
        linear = (self.exE.sum(axis=1) == 1) & (self.exE[:, :n].sum(axis=1) == 1)
        return self.A + self.E[:, linear] @ self.exE[linear, :n]

    def _rescaled_nonlinearity(self, state_scale, input_scale, output_scale):
        """E, F and bounds for :meth:`rescaled`."""
        var_scale = np.concatenate([state_scale, input_scale])
        # zeta(x_n, u_n)_j = zeta_j(x, u) / prod(scale ** exponent)
        return {
            "E": np.diag(state_scale) @ self.E / np.prod(var_scale**self.exE, axis=1),
            "F": np.diag(output_scale) @ self.F / np.prod(var_scale**self.exF, axis=1),
            "bounds": self.bounds * var_scale[:, None],
        }

    def bounded_variables(self, states_inputs):
        """The monomials' variables ``[x; u]`` themselves: what ``bounds``
        bounds."""
        return states_inputs

    def _run(self, U, x0):
        lo, hi = self._bounds()
        return pnlss_simulate(self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF, lo, hi, U, x0)

    def _records_a_thread(self, record_samples):
        """All the check records in one thread: the kernel simulates them
        side by side, in vectors, and half of them cost it about as much as
        all (Bouc-Wen: 4 records 9.2 ms, 8 records 11.4 ms; 10 states and
        275 monomials: 4 and 4 in two threads 242 ms, 8 in one 242 ms)."""
        return CHECK_RECORDS

    def _excursions_in_turn(self, U, n_records, r0, r1, factor, stop_at_first, out):
        """The records side by side in one compiled kernel: the excursions
        of one input at a time, three times as fast."""
        lo, hi = self._bounds()
        pnlss_excursions_in_turn(self.A, self.B, self.E, self.exE, lo, hi, U, n_records, r0, r1, factor,
                                 stop_at_first, out)

    def _span_columns(self):
        """The fewest columns of the sensitivity recursion worth a thread
        (see SPAN_WORK_RATIO)."""
        n, p = self.A.shape[0], self.C.shape[0]
        degree = max(1, int(self.exE.sum(axis=1).max(initial=0)), int(self.exF.sum(axis=1).max(initial=0)))
        repeated = (np.count_nonzero(self.exE[:, :n]) * (degree + n) + np.count_nonzero(self.exF[:, :n]) * (degree + p)
                    + self.exE.shape[0] + self.exF.shape[0])
        return max(1, -(-SPAN_WORK_RATIO * repeated // ((n + p) * n)))

    def _sensitivity(self, U, x, Sx, n_skip, J):
        lo, hi = self._bounds()
        x_end = np.empty_like(x)

        def span(c0, c1):
            pnlss_jacobian(self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF, lo, hi, U, x, x_end,
                           Sx, n_skip, J, c0, c1)

        over_column_spans(span, Sx.shape[1], self._span_columns())
        x[:] = x_end
