"""Levenberg-Marquardt on a simulation error, the PNLSS toolbox's way.

Jacobian columns scaled to unit rms, the step solved by a thin SVD, the
``n_drop`` smallest singular values dropped (the state basis of a state-space
model is not unique: n^2 directions leave the output unchanged), lambda
halved on success and multiplied by 10 on failure, only improving iterates
accepted (so the returned one is the best met). A trial step whose
simulation diverges counts as a failure, never as a result.
"""
from dataclasses import dataclass, field

import numpy as np

__all__ = ["LMResult", "levenberg_marquardt"]


@dataclass
class LMResult:
    theta: np.ndarray
    cost: float
    n_iter: int
    history: list = field(default_factory=list)  # (iteration, cost, lambda)


def levenberg_marquardt(
    residual, jacobian, theta0, *, n_drop=0, max_iter=100, tol=1e-10,
    max_lambda=1e12, callback=None,
):
    """Minimise ``||residual(theta)||^2``.

    Parameters
    ----------
    residual : callable theta -> ndarray or None
        Weighted residual vector; None when the model diverges.
    jacobian : callable theta -> ndarray (n_residuals, n_params)
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
    callback : callable (iteration, cost, lam) or None
        Called after each accepted step (progress display).

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
        J = jacobian(theta)
        scale = np.sqrt(np.mean(J**2, axis=0))
        scale[scale == 0] = 1.0
        U, S, Vt = np.linalg.svd(J / scale, full_matrices=False)
        keep = max(S.size - n_drop, 1)
        U, S, Vt = U[:, :keep], S[:keep], Vt[:keep]
        Ute = U.T @ e
        if lam is None:
            lam = S[0]
        improved = False
        while lam <= max_lambda * S[0]:
            step = -(Vt.T @ (S / (S**2 + lam**2) * Ute)) / scale
            trial = theta + step
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
            callback(it, cost, lam)
        if not improved or rel < tol:
            break
    return LMResult(theta=theta, cost=cost, n_iter=it, history=history)
