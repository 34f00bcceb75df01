"""Univariate branches ``g_l`` of a decoupled polynomial map.

After the CPD ``J ~ [[W, V, H]]`` of the Jacobian tensor, ``H[k, l]``
samples the derivative ``g_l'(z)`` at ``z = v_l^T s_k``. A polynomial fit of
``g_l'`` and its integration give the branches of
``f(s) ~ W g(V^T s)``.

One convention throughout the library (these functions, the decoupled
model, its compiled kernels and ``DecoupledPNLSSRegressor.coef_``): a branch
of degree ``d`` is ``g_l(z) = sum_{k=0..d-1} coef[l, k] z**(k+1)``, a
coefficient array of shape (r, d). It has no constant term (a constant shift
of the state equation is not part of the model). Its linear term
``coef[:, 0]`` is redundant with ``A, B, C, D``: :func:`fit_branches` leaves
it at zero, the fit may move it.

:func:`evaluate_branches` and :func:`branch_derivatives` are the Python twins
of the compiled kernels' branch evaluation, trusted range included. With
``signed=True`` the powers are signed, ``z |z| ** k`` in place of
``z ** (k + 1)``: the same for odd degrees, ``sign(z) z ** (k + 1)`` for even
ones (odd branches).
"""
import numbers

import numpy as np
from sklearn.utils.validation import check_array

from ..statespace.splines import branch_basis, spline_knots

__all__ = [
    "branch_derivatives",
    "decoupled_map",
    "evaluate_branches",
    "fit_branches",
    "splines_from_polynomials",
]


def _check_coef(coef):
    coef = check_array(coef, dtype=np.float64, input_name="coef")
    return coef


def _check_Z(coef, Z):
    Z = check_array(Z, dtype=np.float64, input_name="Z")
    if Z.shape[1] != coef.shape[0]:
        raise ValueError(
            f"Z has {Z.shape[1]} column(s) but coef has {coef.shape[0]} "
            "row(s): one column of Z per branch is needed."
        )
    return Z


def fit_branches(V, H, points, degree, signed=False):
    """Polynomial branches from the CPD factors ``V`` and ``H``.

    For branch ``l``, ``z_l = points @ V[:, l]`` and ``H[:, l]`` samples
    ``g_l'(z_l)``. ``g_l'`` is fitted by least squares as a polynomial in
    ``z`` of degrees 1..``degree - 1`` and integrated to ``g_l`` of degrees
    2..``degree``.

    Parameters
    ----------
    V : array-like of shape (n_vars, r)
        Variable factor of the CPD (one direction ``v_l`` per column).
    H : array-like of shape (N, r)
        Point factor of the CPD, ``H[k, l] ~ g_l'(points[k] @ V[:, l])``.
    points : array-like of shape (N, n_vars)
        The points at which the Jacobian tensor was sampled.
    degree : int
        Degree ``d >= 2`` of the branches ``g_l``.
    signed : bool, default=False
        Signed powers: ``g_l'`` fitted in ``|z| ** p`` (the derivative of
        ``z |z| ** p`` is ``(p + 1) |z| ** p``).

    Returns
    -------
    coef : ndarray of shape (r, degree)
        ``coef[l, k]`` multiplies ``z ** (k + 1)`` in ``g_l``; the linear
        column ``coef[:, 0]`` is zero.

    Notes
    -----
    A constant in ``g_l'`` (a linear term of ``f``) is fitted, so that it
    does not leak into the other coefficients, and then dropped: it is a
    linear term of ``g_l``, which belongs to ``A, B`` (``C, D``), not to the
    nonlinear branches.

    The fit is in ``t = z / rms(z)``, so the columns ``t**p`` of the
    regression matrix are of order one whatever the units of ``z``; the
    coefficients are then mapped back to ``z`` (``c_p = a_p / rms(z)**p``).

    Examples
    --------
    >>> import numpy as np
    >>> z = np.linspace(-1.0, 1.0, 11)
    >>> H = (2 * z + 3 * z**2)[:, None]  # g'(z) of g(z) = z**2 + z**3
    >>> fit_branches([[1.0]], H, z[:, None], degree=3).round(12).tolist()
    [[0.0, 1.0, 1.0]]
    """
    V = check_array(V, dtype=np.float64, input_name="V")
    H = check_array(H, dtype=np.float64, input_name="H")
    points = check_array(points, dtype=np.float64, input_name="points")
    if (
        not isinstance(degree, numbers.Integral)
        or isinstance(degree, bool)
        or degree < 2
    ):
        raise ValueError(
            f"degree must be an integer >= 2 (branches have degrees 2..degree); "
            f"got {degree!r}."
        )
    if points.shape[1] != V.shape[0]:
        raise ValueError(
            f"points has {points.shape[1]} column(s) but V has {V.shape[0]} "
            "row(s): one column per variable is needed."
        )
    if H.shape != (points.shape[0], V.shape[1]):
        raise ValueError(
            f"H must have shape (N, r) = ({points.shape[0]}, {V.shape[1]}) "
            f"(one row per point, one column per branch); got {H.shape}."
        )
    degree = int(degree)
    Z = points @ V
    coef = np.zeros((V.shape[1], degree))
    # Derivative degrees 0..d-1; degree 0 is only there to absorb a constant.
    powers = np.arange(degree)
    for branch in range(V.shape[1]):
        z = Z[:, branch]
        rms = np.sqrt(np.mean(z**2))
        # rms = 0: every point is orthogonal to v_l, g_l' is only seen at 0
        # and its higher coefficients are undetermined; lstsq then returns
        # the minimum-norm answer (zeros) instead of dividing by zero.
        scale = rms if rms > 0 else 1.0
        design = ((np.abs(z) if signed else z) / scale)[:, None] ** powers
        a = np.linalg.lstsq(design, H[:, branch], rcond=None)[0]
        deriv = a[1:] / scale ** powers[1:]  # g_l' coefficients of z**1..z**(d-1)
        coef[branch, 1:] = deriv / (powers[1:] + 1)  # integrate: z**p -> z**(p+1)/(p+1)
    return coef


def splines_from_polynomials(coef, Z, n_basis, margin=0.1):
    """Spline branches that follow polynomial branches over their inputs.

    Each branch gets knots spanning its inputs ``Z[:, l]`` (widened by
    ``margin`` of their range on each side) and the spline coefficients
    that fit its polynomial best, by least squares on a fine grid over the
    knots: how a start made for polynomials (a CPD, random branches) starts
    spline branches.

    Parameters
    ----------
    coef : array-like of shape (r, degree)
        Polynomial branches (see :func:`fit_branches`).
    Z : array-like of shape (N, r)
        Branch inputs the splines must cover.
    n_basis : int
        Coefficients per spline, at least 4.
    margin : float, default=0.1

    Returns
    -------
    spline_coef : ndarray of shape (r, n_basis)
    knots : ndarray of shape (r, 2)
        ``[first knot, spacing]`` of each branch.

    Examples
    --------
    >>> import numpy as np
    >>> z = np.linspace(-1.0, 1.0, 101)[:, None]
    >>> c, knots = splines_from_polynomials([[0.0, 1.0, 1.0]], z, 6)  # z**2 + z**3: a cubic, exact
    >>> float(np.abs(evaluate_branches(c, z, knots=knots) - (z**2 + z**3)).max()) < 1e-12
    True
    """
    coef = _check_coef(coef)
    Z = _check_Z(coef, Z)
    knots = np.vstack([spline_knots(z, n_basis, margin) for z in Z.T])
    spline_coef = np.empty((coef.shape[0], n_basis))
    for l, k in enumerate(knots):
        grid = np.linspace(k[0], k[0] + (n_basis - 3) * k[1], 10 * n_basis)
        basis = branch_basis(grid, k, n_basis)[0]
        target = evaluate_branches(coef[l : l + 1], grid[:, None])[:, 0]
        spline_coef[l] = np.linalg.lstsq(basis, target, rcond=None)[0]
    return spline_coef, knots


def _held(coef, Z, bounds):
    """``coef`` and ``Z`` checked, and ``Z`` held inside ``bounds`` (r, 2)."""
    coef = _check_coef(coef)
    Z = _check_Z(coef, Z)
    if bounds is None:
        return coef, Z, Z
    bounds = np.asarray(bounds, dtype=np.float64)
    if bounds.shape != (coef.shape[0], 2):
        raise ValueError(f"bounds must have shape (r, 2) = ({coef.shape[0]}, 2); got {bounds.shape}.")
    return coef, Z, np.clip(Z, bounds[:, 0], bounds[:, 1])


def _branch_functions(coef, Z, knots, signed=False):
    """g and g' of the plain polynomials (``knots`` None; in signed powers
    when ``signed``) or splines at Z (N, r)."""
    if knots is not None:
        knots = np.asarray(knots, dtype=np.float64)
        if knots.shape != (coef.shape[0], 2):
            raise ValueError(f"knots must have shape (r, 2) = ({coef.shape[0]}, 2); got {knots.shape}.")
        g, dg = np.empty_like(Z), np.empty_like(Z)
        for l, (c, k) in enumerate(zip(coef, knots)):
            B, dB = branch_basis(Z[:, l], k, c.size)
            g[:, l] = B @ c
            dg[:, l] = dB @ c
        return g, dg
    # z**k, k = 0..d-1; signed: |z|**k, and z |z|**k for z**(k + 1)
    powers = (np.abs(Z) if signed else Z)[:, :, None] ** np.arange(coef.shape[1])
    k1 = np.arange(1, coef.shape[1] + 1)
    return np.einsum("nlk,lk->nl", powers * Z[:, :, None], coef), np.einsum("nlk,lk->nl", powers, coef * k1)


def evaluate_branches(coef, Z, bounds=None, linear_extrapolation=False, knots=None, signed=False):
    """Values of the branches, ``G[k, l] = g_l(Z[k, l])``, as the decoupled
    model evaluates them.

    Parameters
    ----------
    coef : array-like of shape (r, degree)
        Branch coefficients, ``coef[l, k]`` multiplies ``z ** (k + 1)``.
    Z : array-like of shape (N, r)
        Branch arguments, ``Z = points @ V``.
    bounds : array-like of shape (r, 2) or None, default=None
        Trusted range of each branch input; outside it the branch keeps its
        edge value, or, with ``linear_extrapolation``, follows its edge
        tangent. None: the plain polynomials.
    linear_extrapolation : bool, default=False
    knots : array-like of shape (r, 2) or None, default=None
        Spline branches: ``[first knot, spacing]`` of each, ``coef[l, k]``
        multiplying ``B_k(z) - B_k(0)`` (see
        :mod:`sklearn_pnlss.statespace.splines`); None: polynomials.
    signed : bool, default=False
        Polynomials in signed powers, ``coef[l, k]`` multiplying
        ``z |z| ** k``.

    Returns
    -------
    G : ndarray of shape (N, r)

    Examples
    --------
    >>> evaluate_branches([[0.0, 1.0, 1.0]], [[2.0]]).tolist()  # z**2 + z**3 at 2
    [[12.0]]
    >>> evaluate_branches([[0.0, 1.0, 1.0]], [[3.0]], bounds=[[-2.0, 2.0]]).tolist()  # held at 2
    [[12.0]]
    >>> evaluate_branches([[0.0, 1.0, 1.0]], [[3.0]], [[-2.0, 2.0]], linear_extrapolation=True).tolist()
    [[28.0]]
    >>> evaluate_branches([[0.0, 1.0, 1.0]], [[-2.0]], signed=True).tolist()  # z|z| + z**3 at -2
    [[-12.0]]
    """
    coef, Z, Zc = _held(coef, Z, bounds)
    g, dg = _branch_functions(coef, Zc, knots, signed)
    return g + dg * (Z - Zc) if linear_extrapolation else g


def branch_derivatives(coef, Z, bounds=None, linear_extrapolation=False, knots=None, signed=False):
    """Derivatives of the branches, ``G'[k, l] = g_l'(Z[k, l])``, as the
    decoupled model evaluates them (zero where a branch is held, the edge
    slope where it follows its tangent).

    Parameters
    ----------
    coef, Z, bounds, linear_extrapolation, knots, signed
        As in :func:`evaluate_branches`.

    Returns
    -------
    dG : ndarray of shape (N, r)

    Examples
    --------
    >>> branch_derivatives([[0.0, 1.0, 1.0]], [[2.0]]).tolist()  # 2z + 3z**2 at 2
    [[16.0]]
    """
    coef, Z, Zc = _held(coef, Z, bounds)
    dg = _branch_functions(coef, Zc, knots, signed)[1]
    return dg if linear_extrapolation else np.where(Z == Zc, dg, 0.0)


def decoupled_map(W, V, coef, points):
    """The decoupled map ``f(s) = W g(V^T s)`` at many points.

    Used to check a decoupled approximation against the original
    polynomial ``E zeta(s)``.

    Parameters
    ----------
    W : array-like of shape (n_out, r)
        Output factor (how the branches combine into the outputs).
    V : array-like of shape (n_vars, r)
        Variable factor (one direction per branch).
    coef : array-like of shape (r, degree)
        Branch coefficients (see :func:`fit_branches`).
    points : array-like of shape (N, n_vars)
        Where to evaluate, one point per row.

    Returns
    -------
    values : ndarray of shape (N, n_out)
        ``values[k] = W @ g(V.T @ points[k])``.

    Examples
    --------
    >>> # one branch g(z) = z**2 along v = (1, 1), fed to two outputs
    >>> decoupled_map([[1.0], [2.0]], [[1.0], [1.0]], [[0.0, 1.0]], [[1.0, 2.0]]).tolist()
    [[9.0, 18.0]]
    """
    W = check_array(W, dtype=np.float64, input_name="W")
    V = check_array(V, dtype=np.float64, input_name="V")
    coef = _check_coef(coef)
    points = check_array(points, dtype=np.float64, input_name="points")
    if not W.shape[1] == V.shape[1] == coef.shape[0]:
        raise ValueError(
            f"W has {W.shape[1]} column(s), V {V.shape[1]} column(s) and coef "
            f"{coef.shape[0]} row(s): all must equal the number of branches r."
        )
    if points.shape[1] != V.shape[0]:
        raise ValueError(
            f"points has {points.shape[1]} column(s) but V has {V.shape[0]} "
            "row(s): one column per variable is needed."
        )
    return evaluate_branches(coef, points @ V) @ W.T
