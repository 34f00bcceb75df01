"""The Jacobian tensor of a multivariate polynomial, sampled at many points.

Decoupling starts from the nonlinear part of a PNLSS model,
``f(s) = E @ zeta(s)`` with ``s = [x; u]``. Its first-order information at
``N`` operating points, stacked as an ``n_out x n_vars x N`` tensor, has a
low-rank canonical polyadic structure exactly when ``f`` is (close to) a sum
of univariate branches ``W g(V^T s)``; see :mod:`sklearn_pnlss.decoupling.cpd`.
"""
import numbers

import numpy as np
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_array

__all__ = ["polynomial_jacobian", "polynomial_map", "sample_points"]


def _check_polynomial(E, exponents, points):
    """Validated float ``E``, int ``exponents`` and float ``points``."""
    E = check_array(E, dtype=np.float64, input_name="E", ensure_min_features=0)
    exponents = np.asarray(exponents)
    if exponents.ndim != 2:
        raise ValueError(
            "exponents must be a 2-D array (n_terms, n_vars); got an array "
            f"with {exponents.ndim} dimension(s)."
        )
    # Accept integer-valued floats (e.g. loaded from a .mat file), but never
    # silently truncate 1.5 to 1: that would be another polynomial.
    is_int = exponents.dtype.kind in "iu" or (
        exponents.dtype.kind == "f"
        and np.all(np.isfinite(exponents) & (exponents == np.round(exponents)))
    )
    if not is_int:
        raise ValueError("exponents must hold non-negative integers.")
    exponents = exponents.astype(np.int64)
    if np.any(exponents < 0):
        raise ValueError("exponents must hold non-negative integers.")
    if E.shape[1] != exponents.shape[0]:
        raise ValueError(
            f"E has {E.shape[1]} column(s) but exponents has "
            f"{exponents.shape[0]} row(s): one exponent row per column of E "
            "(monomial) is needed."
        )
    points = check_array(points, dtype=np.float64, input_name="points")
    if points.shape[1] != exponents.shape[1]:
        raise ValueError(
            f"points has {points.shape[1]} column(s) but exponents has "
            f"{exponents.shape[1]}: one column per variable is needed."
        )
    return E, exponents, points


def _power_table(points, max_degree):
    """``table[k, v, p] = points[k, v] ** p`` for ``p = 0..max_degree``.

    Every monomial is then a product of looked-up entries, so each power is
    computed once instead of once per monomial.
    """
    return points[:, :, None] ** np.arange(max_degree + 1)


def _monomials(table, exponents):
    """``zeta[k, j] = prod_v table[k, v, exponents[j, v]]``, shape (N, n_terms)."""
    n_vars = exponents.shape[1]
    # Fancy indexing: for every (term j, variable v) pick power exponents[j, v]
    # of variable v at every point -> (N, n_terms, n_vars).
    return table[:, np.arange(n_vars)[None, :], exponents].prod(axis=-1)


def polynomial_map(E, exponents, points):
    """Evaluate the polynomial map ``f(s) = E @ zeta(s)`` at many points.

    Parameters
    ----------
    E : array-like of shape (n_out, n_terms)
        Coefficients, one column per monomial.
    exponents : array-like of int of shape (n_terms, n_vars)
        ``zeta(s)_j = prod_v s_v ** exponents[j, v]``.
    points : array-like of shape (N, n_vars)
        Where to evaluate, one point per row.

    Returns
    -------
    values : ndarray of shape (N, n_out)
        ``values[k] = f(points[k])``.

    Examples
    --------
    >>> polynomial_map([[1.0, 2.0]], [[2, 0], [1, 1]], [[3.0, 1.0]]).tolist()
    [[15.0]]
    """
    E, exponents, points = _check_polynomial(E, exponents, points)
    max_degree = int(exponents.max()) if exponents.size else 0
    zeta = _monomials(_power_table(points, max_degree), exponents)
    return zeta @ E.T


def polynomial_jacobian(E, exponents, points):
    """Jacobian tensor of ``f(s) = E @ zeta(s)`` at many points.

    Parameters
    ----------
    E : array-like of shape (n_out, n_terms)
        Coefficients, one column per monomial.
    exponents : array-like of int of shape (n_terms, n_vars)
        ``zeta(s)_j = prod_v s_v ** exponents[j, v]``, e.g. from
        :func:`sklearn_pnlss.statespace.monomials.monomial_exponents`.
    points : array-like of shape (N, n_vars)
        Where to differentiate, one point per row.

    Returns
    -------
    J : ndarray of shape (n_out, n_vars, N)
        ``J[i, v, k] = d f_i / d s_v`` at ``points[k]``.

    Notes
    -----
    The derivative is exact (analytic): ``d zeta_j / d s_v = a_jv *
    s_v ** (a_jv - 1) * prod_{w != v} s_w ** a_jw``. The reduced exponent
    ``a_jv - 1`` is clipped at 0 where ``a_jv = 0``; the factor ``a_jv = 0``
    then zeroes the term, so no ``0 ** -1`` (division by zero) ever occurs,
    even at points with zero coordinates.

    Examples
    --------
    >>> # f(s) = s0**2 * s1, so df/ds0 = 2 s0 s1 and df/ds1 = s0**2
    >>> polynomial_jacobian([[1.0]], [[2, 1]], [[3.0, 2.0]]).tolist()
    [[[12.0], [9.0]]]
    """
    E, exponents, points = _check_polynomial(E, exponents, points)
    n_out = E.shape[0]
    n_points, n_vars = points.shape
    max_degree = int(exponents.max()) if exponents.size else 0
    table = _power_table(points, max_degree)
    J = np.empty((n_out, n_vars, n_points))
    # The loop runs over the few variables (n_vars = n + n_inputs), never over
    # the points; each pass is one vectorised table look-up and one matmul.
    for v in range(n_vars):
        reduced = exponents.copy()
        reduced[:, v] = np.maximum(reduced[:, v] - 1, 0)
        dzeta = _monomials(table, reduced) * exponents[:, v]
        J[:, v, :] = E @ dzeta.T
    return J


def sample_points(trajectory, n_points=500, random_state=None):
    """Draw points where the model actually operates.

    The decoupled approximation is only asked to be good where the model's
    states and inputs go: a polynomial that is decoupled on that region but
    not far outside it is fine, while points drawn from an arbitrary box
    would spend the fit on regions the model never visits (where high-degree
    terms blow up). So the points are rows of a simulated trajectory.

    Parameters
    ----------
    trajectory : array-like of shape (n_samples, n_vars)
        States and inputs along a simulation, ``s(t) = [x(t); u(t)]``.
    n_points : int, default=500
        Number of points ``N`` (the reference paper uses 500).
    random_state : int, RandomState, Generator or None, default=None
        Controls which rows are drawn.

    Returns
    -------
    points : ndarray of shape (n_points, n_vars)
        Rows of ``trajectory`` drawn at random without replacement, or with
        replacement when the trajectory has fewer than ``n_points`` rows.

    Examples
    --------
    >>> import numpy as np
    >>> trajectory = np.arange(20.0).reshape(10, 2)
    >>> sample_points(trajectory, n_points=4, random_state=0).shape
    (4, 2)
    """
    trajectory = check_array(trajectory, dtype=np.float64, input_name="trajectory")
    if (
        not isinstance(n_points, numbers.Integral)
        or isinstance(n_points, bool)
        or n_points < 1
    ):
        raise ValueError(f"n_points must be a positive integer; got {n_points!r}.")
    # A numpy Generator has the same ``choice`` signature; everything else
    # goes through scikit-learn's usual seed handling.
    if isinstance(random_state, np.random.Generator):
        rng = random_state
    else:
        rng = check_random_state(random_state)
    n_samples = trajectory.shape[0]
    rows = rng.choice(n_samples, size=int(n_points), replace=n_samples < n_points)
    return trajectory[rows]
