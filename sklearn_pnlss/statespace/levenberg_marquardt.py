"""Levenberg-Marquardt on a simulation error, the PNLSS toolbox's way.

Jacobian columns scaled to unit rms, the step solved in the basis of the
right singular vectors of the scaled Jacobian, the ``n_drop`` smallest
singular values dropped (the state basis of a state-space model is not
unique: n^2 directions leave the output unchanged), lambda halved on success
and multiplied by 10 on failure, only improving iterates accepted (so the
returned one is the best met). A trial step whose simulation diverges counts
as a failure, never as a result.

The singular values and right singular vectors come from the eigenvalues of
J^T J rather than from an SVD of J. Both give the same step; the normal
equations are accumulated segment by segment, so the Jacobian is never held
whole (memory), and a (n_params x n_params) eigenproblem replaces an SVD of a
(n_samples x n_params) matrix (time: 6 ms instead of 90 ms on the Bouc-Wen
training record). The precision lost by squaring J only affects directions
whose singular values are below sqrt(eps) of the largest; those are dropped.

A model may also give a ``basis``: the step is then solved in the
coordinates ``phi`` of ``theta = theta_k + basis @ phi``. It is the same
model and the same cost; only the step changes, since the damping is
isotropic in the scaled coordinates it is solved in. Column scaling cannot
decorrelate nearly collinear columns (the powers ``z**9`` and ``z**11`` of a
polynomial branch); a basis of polynomials orthogonal on the branch's range
does, and the steps then go where plain monomials stall (see
:meth:`~sklearn_pnlss.statespace.decoupled.DecoupledModel.step_basis`).
"""
from dataclasses import dataclass, field

import numpy as np

__all__ = ["LMResult", "levenberg_marquardt", "lm_step_basis"]


@dataclass
class LMResult:
    theta: np.ndarray
    cost: float
    n_iter: int
    history: list = field(default_factory=list)  # (iteration, cost, lambda)


def lm_step_basis(G, n_drop):
    """Column scales, kept singular values and right singular vectors of the
    column-scaled Jacobian, from its Gram matrix ``G = J^T J``.

    Returns ``scale`` (n_params,), ``S`` (k,) descending, ``V`` (n_params, k).
    """
    scale = np.sqrt(np.diag(G))
    scale[scale == 0] = 1.0
    w, V = np.linalg.eigh(G / np.outer(scale, scale))
    w, V = w[::-1], V[:, ::-1]
    keep = max(w.size - n_drop, 1)
    # Below eps * largest, an eigenvalue of the Gram matrix is rounding noise.
    keep = max(min(keep, int(np.sum(w > w[0] * w.size * np.finfo(float).eps))), 1)
    return scale, np.sqrt(np.maximum(w[:keep], 0.0)), V[:, :keep]


def levenberg_marquardt(
    residual, normal_equations, theta0, *, n_drop=0, max_iter=100, tol=1e-10,
    max_lambda=1e12, callback=None, basis=None,
):
    """Minimise ``||residual(theta)||^2``.

    Parameters
    ----------
    residual : callable theta -> ndarray or None
        Weighted residual vector; None when the model diverges.
    normal_equations : callable theta -> (G, g)
        ``J^T J`` and ``J^T e`` of the residual at theta.
    theta0 : ndarray
        Start; its residual must be finite.
    n_drop : int
        Smallest singular values to drop from each step.
    max_iter : int
        Jacobian evaluations at most.
    tol : float
        Stop when an accepted step lowers the cost by less than this fraction.
    max_lambda : float
        Stop when lambda grows past this (relative to the largest singular
        value): no descent direction is left.
    callback : callable (iteration, theta, cost, lam) or None
        Called after each iteration (progress, validation).
    basis : ndarray of shape (n_params, n_params) or None
        Invertible: each step is ``basis @ phi`` with ``phi`` solved from the
        Jacobian ``J @ basis``. None: the identity.

    Returns
    -------
    LMResult
    """
    theta = np.array(theta0, dtype=float)
    e = residual(theta)
    if e is None or not np.all(np.isfinite(e)):
        raise ValueError("The starting model diverges on the training data; cannot optimise from it.")
    cost = float(e @ e)
    history = [(0, cost, np.nan)]
    lam = None
    it = 0
    for it in range(1, max_iter + 1):
        G, g = normal_equations(theta)
        if basis is not None:
            G, g = basis.T @ G @ basis, basis.T @ g
        scale, S, V = lm_step_basis(G, n_drop)
        Vg = V.T @ (g / scale)
        if lam is None:
            lam = S[0]
        improved = False
        while lam <= max_lambda * S[0]:
            # Scaled step -V diag(1 / (S^2 + lam^2)) V^T J^T e, then unscaled.
            step = (V @ (Vg / (S**2 + lam**2))) / scale
            trial = theta - (step if basis is None else basis @ step)
            e_new = residual(trial)
            if e_new is not None and np.all(np.isfinite(e_new)):
                cost_new = float(e_new @ e_new)
                if cost_new < cost:
                    rel = (cost - cost_new) / cost
                    theta, e, cost = trial, e_new, cost_new
                    lam /= 2
                    improved = True
                    break
            lam *= 10
        history.append((it, cost, lam))
        if callback is not None:
            callback(it, theta, cost, lam)
        if not improved or rel < tol:
            break
    return LMResult(theta=theta, cost=cost, n_iter=it, history=history)
