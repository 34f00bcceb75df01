"""The polynomial nonlinear state-space model: parameters, simulation of
signals (from rest or in periodic steady state), residuals and exact
Jacobians over a set of training segments."""
from dataclasses import dataclass

import numpy as np

from ._pnlss_kernels import pnlss_jacobian, pnlss_simulate

__all__ = ["PNLSSModel", "Segment", "DivergenceError"]


class DivergenceError(ValueError):
    """The model's simulation left any reasonable range."""


@dataclass
class Segment:
    """One training signal ready for simulation: ``U`` is simulated from rest
    and the first ``n_skip`` samples (a transient) are left out of the cost.

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


@dataclass
class PNLSSModel:
    """x(t+1) = A x + B u + E zeta([x; u]), y = C x + D u + F eta([x; u]).

    ``exE`` / ``exF`` hold the monomial exponents over the variables
    ``[x; u]``. Parameter vector order: A, B, E, C, D, F (row-major).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    E: np.ndarray
    F: np.ndarray
    exE: np.ndarray
    exF: np.ndarray

    @property
    def blocks(self):
        return (self.A, self.B, self.E, self.C, self.D, self.F)

    @property
    def theta(self):
        return np.concatenate([M.ravel() for M in self.blocks])

    def with_theta(self, theta):
        parts, i = [], 0
        for M in self.blocks:
            parts.append(theta[i : i + M.size].reshape(M.shape).copy())
            i += M.size
        A, B, E, C, D, F = parts
        return PNLSSModel(A, B, C, D, E, F, self.exE, self.exF)

    @property
    def n_params(self):
        return sum(M.size for M in self.blocks)

    def _run(self, U, x0):
        return pnlss_simulate(
            self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF,
            np.ascontiguousarray(U), x0,
        )

    def simulate(self, U, x0=None):
        """Output and final state from ``x0`` (zero by default); raises
        :class:`DivergenceError` when the state leaves the range."""
        x0 = np.zeros(self.A.shape[0]) if x0 is None else x0
        Y, _, n_ok, x_end = self._run(U, x0)
        if n_ok < U.shape[0]:
            raise DivergenceError(f"the simulation diverges at sample {n_ok}")
        return Y, x_end

    def steady_state_start(self, U_period, max_periods=200, rtol=1e-10):
        """State at the start of a period once the response is periodic:
        period after period from rest until the state repeats."""
        x = np.zeros(self.A.shape[0])
        for _ in range(max_periods):
            _, x_new = self.simulate(U_period, x)
            done = np.linalg.norm(x_new - x) <= rtol * (1.0 + np.linalg.norm(x_new))
            x = x_new
            if done:
                break
        return x

    def simulate_signal(self, U, period=None):
        """Simulate one signal; periodic steady state when ``period`` is
        given (the length is a multiple of it), else from rest."""
        x0 = None if period is None else self.steady_state_start(U[:period])
        return self.simulate(U, x0)[0]

    def segment_error(self, seg):
        """Simulation error (T, p) on one segment, or None when it diverges."""
        Y, _, n_ok, _ = self._run(seg.U, np.zeros(self.A.shape[0]))
        if n_ok < seg.U.shape[0]:
            return None
        return Y[seg.n_skip :] - seg.Y

    def segment_jacobian(self, seg):
        """Exact Jacobian (T, p, n_params) of :meth:`segment_error` by the
        sensitivity recursion."""
        J = np.empty((seg.U.shape[0] - seg.n_skip, self.C.shape[0], self.n_params))
        pnlss_jacobian(
            self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF,
            np.ascontiguousarray(seg.U), np.zeros(self.A.shape[0]), seg.n_skip, J,
        )
        return J

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
