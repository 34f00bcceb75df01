"""Least squares of one trial column beside fixed columns, for many trial
columns at once.

A start searched on a grid (a backlash's clearance, a second mode's
frequency and damping) solves ``b ~ c h + L d`` for every grid point's
column ``h``, with the same fixed columns ``L`` (the freed nominal
parameters) and the same target ``b``. With the range of ``L`` projected
out once, each ``h`` costs a few dot products:
``|P b|^2 - (h' P b)^2 / (h' P h)``, where ``P`` projects on the complement
of that range. One ``lstsq`` per grid point was most of a start's time
(4,800 solves per second-mode start, 200 per clearance search and its
refinement; 9 s of a 78 s diagnosis of a stiff backlash).
"""
import numpy as np

__all__ = ["TrialColumns"]


class TrialColumns:
    """The fixed columns ``L`` and target ``b`` of many trial fits.

    Parameters
    ----------
    fixed : ndarray of shape (n, k)
        The fixed columns (k may be 0).
    target : ndarray of shape (n,)
    """

    def __init__(self, fixed, target):
        self.fixed = _as_columns(fixed)
        self.target = np.asarray(target, float)
        self._basis, self._top = _range_basis(self.fixed)
        self._residual = self._projected(self.target)
        #: the cost with the fixed columns alone
        self.base_cost = float(self._residual @ self._residual)

    def _projected(self, a):
        """``a`` less its part in the range of the fixed columns."""
        return a - self._basis @ (self._basis.T @ a)

    def costs(self, columns):
        """The cost left by each trial column (the columns of ``columns``,
        shape (n, m)) fitted with the fixed ones; a zero column leaves
        :attr:`base_cost`."""
        columns = _as_columns(columns)
        r = self._projected(columns)
        num = r.T @ self._residual
        den = np.einsum("ij,ij->j", r, r)
        # a column within round-off of the fixed ones' range adds nothing,
        # as lstsq's rank cut (relative to the largest singular value) has it
        scale = np.maximum(np.einsum("ij,ij->j", columns, columns), self._top**2)
        free = den > (max(columns.shape[0], self.fixed.shape[1] + 1) * np.finfo(float).eps) ** 2 * scale
        return np.where(free, self.base_cost - num**2 / np.where(free, den, 1.0), self.base_cost)

    def solve(self, column):
        """Coefficients of ``[column, fixed]`` (the trial column's first) and
        the cost they leave: ``numpy.linalg.lstsq``'s solution."""
        A = np.column_stack([column, self.fixed])
        coef = np.linalg.lstsq(A, self.target, rcond=None)[0]
        return coef, float(np.sum((self.target - A @ coef) ** 2))


def _range_basis(a):
    """Orthonormal basis of the range of ``a``, cut at lstsq's default rank
    tolerance, and ``a``'s largest singular value."""
    if a.shape[1] == 0:
        return np.zeros((a.shape[0], 0)), 0.0
    u, s, _ = np.linalg.svd(a, full_matrices=False)
    if s.size == 0 or s[0] == 0:
        return np.zeros((a.shape[0], 0)), 0.0
    rank = int(np.sum(s > s[0] * max(a.shape) * np.finfo(float).eps))
    return u[:, :rank], float(s[0])


def _as_columns(a):
    a = np.asarray(a, float)
    return a[:, None] if a.ndim == 1 else a
