"""Decoupling of a PNLSS polynomial into a few univariate branches.

The start of the decoupled model ``f(s) ~ W g(V^T s)``, in four steps:

1. :func:`sample_points` draws ``N`` points ``s = [x; u]`` along a simulated
   trajectory (where the model operates);
2. :func:`polynomial_jacobian` evaluates the Jacobian of
   ``f(s) = E zeta(s)`` there, an ``n_out x n_vars x N`` tensor;
3. :func:`decompose_jacobian` computes its rank-``r`` CPD ``[[W, V, H]]``
   (:func:`rank_scan` helps choose ``r``);
4. :func:`fit_branches` turns ``H`` into polynomial branches ``g_l`` of
   degrees 2..d (coefficients of shape (r, d), one per degree 1..d); :func:`decoupled_map` evaluates the result;
   :func:`splines_from_polynomials` turns them into spline branches.

Internal: not part of the API; may change without notice (the estimators in
:mod:`sklearn_pnlss` are the way in).
"""
from .branches import (
    branch_derivatives,
    decoupled_map,
    evaluate_branches,
    fit_branches,
    splines_from_polynomials,
)
from .cpd import CPDResult, RankScan, decompose_jacobian, rank_scan
from .jacobian_tensor import polynomial_jacobian, polynomial_map, sample_points

__all__ = [
    "CPDResult",
    "RankScan",
    "branch_derivatives",
    "decompose_jacobian",
    "decoupled_map",
    "evaluate_branches",
    "fit_branches",
    "polynomial_jacobian",
    "polynomial_map",
    "rank_scan",
    "sample_points",
    "splines_from_polynomials",
]
