"""Exponent tables of the multivariate monomials of a PNLSS model."""
from itertools import combinations_with_replacement

import numpy as np

__all__ = ["monomial_exponents"]


def monomial_exponents(n_vars, degrees, active=None):
    """Exponents of all monomials of the given total degrees.

    Parameters
    ----------
    n_vars : int
        Number of variables (states then inputs).
    degrees : iterable of int
        Total degrees to include, e.g. ``(2, 3)``.
    active : array-like of bool of shape (n_vars,), default=None
        Variables allowed in the monomials (others get exponent 0); all when
        None. ``variables="states"`` activates the states only.

    Returns
    -------
    exponents : ndarray of int of shape (n_terms, n_vars)
        One row per monomial, ordered by degree then lexicographically.

    Examples
    --------
    >>> monomial_exponents(2, (2,)).tolist()
    [[2, 0], [1, 1], [0, 2]]
    """
    idx = np.arange(n_vars) if active is None else np.flatnonzero(active)
    rows = []
    for degree in sorted(set(int(d) for d in degrees)):
        for combo in combinations_with_replacement(idx, degree):
            row = np.zeros(n_vars, dtype=np.int64)
            for v in combo:
                row[v] += 1
            rows.append(row)
    if not rows:
        return np.zeros((0, n_vars), dtype=np.int64)
    return np.array(rows, dtype=np.int64)
