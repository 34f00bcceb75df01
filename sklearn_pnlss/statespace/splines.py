"""Uniform cubic B-splines: the spline branches of a decoupled model.

A spline branch with ``d`` coefficients lives on ``d - 3`` equal intervals
between its first knot ``start`` and its last, ``start + (d - 3) spacing``,
and is continued along its edge tangents beyond them. Where a polynomial of
high degree must bend everywhere to follow a knee (a diode, a saturation),
a spline bends only where its data ask it to, and every coefficient acts on
four intervals only, so the coefficients stay well conditioned whatever
their number.

The compiled kernels evaluate the same functions sample by sample
(:mod:`._decoupled_kernels`); these are their vectorised twins, used for the
starts, plots and tests.
"""
import numpy as np

__all__ = ["branch_basis", "cubic_bspline_basis", "greville_points", "spline_knots"]


def spline_knots(z, n_basis, margin=0.1):
    """``[start, spacing]`` of knots spanning the values ``z`` of one branch
    input, widened by ``margin`` times their range on each side (room for
    the fit to move the input before it reaches the linear continuation).

    Examples
    --------
    >>> spline_knots([-1.0, 1.0], 6, margin=0.0).tolist()
    [-1.0, 0.6666666666666666]
    """
    z = np.asarray(z, dtype=float)
    lo, hi = float(z.min()), float(z.max())
    width = hi - lo if hi > lo else 1.0
    lo, hi = lo - margin * width, hi + margin * width
    return np.array([lo, (hi - lo) / (n_basis - 3)])


def greville_points(knots, n_basis):
    """The centre of each B-spline's support: coefficients equal to a
    function's values there reproduce it exactly when it is linear."""
    start, spacing = knots
    return start + (np.arange(n_basis) - 1.0) * spacing


def cubic_bspline_basis(z, knots, n_basis):
    """Values and derivatives of the ``n_basis`` B-splines at ``z``.

    Parameters
    ----------
    z : array-like of shape (N,)
    knots : (start, spacing)
    n_basis : int
        At least 4 (one interval).

    Returns
    -------
    B, dB : ndarray of shape (N, n_basis)
        ``B[i, k] = B_k(z[i])`` and its derivative in ``z``; beyond the
        knots, each ``B_k`` follows its tangent at the nearer edge.

    Examples
    --------
    >>> B, dB = cubic_bspline_basis([0.0, 0.5], (0.0, 1.0), 4)
    >>> B.sum(axis=1).round(12).tolist()  # a partition of unity
    [1.0, 1.0]
    """
    z = np.atleast_1d(np.asarray(z, dtype=float))
    start, spacing = float(knots[0]), float(knots[1])
    n_int = n_basis - 3
    te = np.clip((z - start) / spacing, 0.0, n_int)
    i = np.minimum(te.astype(int), n_int - 1)
    u = te - i
    v = 1.0 - u
    w = np.stack([v**3, 3 * u**3 - 6 * u**2 + 4, -3 * u**3 + 3 * u**2 + 3 * u + 1, u**3], axis=-1) / 6
    dw = np.stack([-(v**2), 3 * u**2 - 4 * u, -3 * u**2 + 2 * u + 1, u**2], axis=-1) / (2 * spacing)
    run = z - (start + te * spacing)  # beyond the knots, the tangent's run
    B = np.zeros((z.size, n_basis))
    dB = np.zeros((z.size, n_basis))
    rows, cols = np.arange(z.size)[:, None], i[:, None] + np.arange(4)
    B[rows, cols] = w + dw * run[:, None]
    dB[rows, cols] = dw
    return B, dB


def branch_basis(z, knots, n_basis):
    """What a spline branch's coefficients multiply, ``B_k(z) - B_k(0)``
    (so that every branch is 0 at 0), and its derivative in ``z``."""
    B, dB = cubic_bspline_basis(z, knots, n_basis)
    return B - cubic_bspline_basis(0.0, knots, n_basis)[0], dB
