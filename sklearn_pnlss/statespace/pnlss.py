"""The polynomial nonlinear state-space model."""
from dataclasses import dataclass

import numpy as np

from ._pnlss_kernels import pnlss_jacobian, pnlss_simulate
from .model_base import DivergenceError, Segment, StateSpaceModel

__all__ = ["DivergenceError", "PNLSSModel", "Segment"]


@dataclass
class PNLSSModel(StateSpaceModel):
    """x(t+1) = A x + B u + E zeta([x; u]), y = C x + D u + F eta([x; u]).

    ``exE`` / ``exF`` hold the monomial exponents over the variables
    ``[x; u]``. Parameter vector order: A, B, E, C, D, F (row-major): the
    blocks that move the state first, as the Jacobian kernel expects.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    E: np.ndarray
    F: np.ndarray
    exE: np.ndarray
    exF: np.ndarray

    _block_names = ("A", "B", "E", "C", "D", "F")

    def _run(self, U, x0):
        return pnlss_simulate(self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF, U, x0)

    def _sensitivity(self, U, x0, n_skip, J):
        pnlss_jacobian(self.A, self.B, self.C, self.D, self.E, self.F, self.exE, self.exF, U, x0, n_skip, J)
