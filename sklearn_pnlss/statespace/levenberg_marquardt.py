"""Levenberg-Marquardt on a simulation error, the PNLSS toolbox's way.

Jacobian columns scaled to unit rms, the step solved in the basis of the
right singular vectors of the scaled Jacobian, the ``n_drop`` smallest
singular values dropped (the state basis of a state-space model is not
unique: n^2 directions leave the output unchanged), only improving iterates
accepted (so the returned one is the best met). A trial step whose
simulation diverges counts as a failure, never as a result.

The damping follows Nielsen's rule (Madsen, Nielsen and Tingleff, *Methods
for non-linear least squares problems*, 2004, section 3.2) rather than the
toolbox's (lambda halved on success, multiplied by 10 on failure): on
success the damping ``mu = lambda^2`` is multiplied by
``max(1/3, 1 - (2 rho - 1)^3)``, where ``rho`` is the cost's fall over the
fall the linearised model predicted; on failure by ``nu``, which doubles at
each failure in a row. A good quadratic model (``rho`` near 1) thus lowers
the damping, a poor one (``rho`` near 0) raises it without a failed
simulation, and one failure costs a factor 2 instead of 100. Measured
(``benchmarks/bench_lm_schedule.py``, 100 iterations from the same
starts): the training cost ends 6.6 dB lower on WH2009 (833 parameters)
and 2.7 dB lower on EMPS, the same on the F-16 and Bouc-Wen, 0.15 dB higher
on the cascaded tanks.

The singular values and right singular vectors come from the eigenvalues of
J^T J rather than from an SVD of J. Both give the same step; the normal
equations are accumulated segment by segment, so the Jacobian is never held
whole (memory), and a (n_params x n_params) eigenproblem replaces an SVD of a
(n_samples x n_params) matrix (time: 6 ms instead of 90 ms on the Bouc-Wen
training record). The precision lost by squaring J only affects directions
whose singular values are below sqrt(eps) of the largest; those are dropped.

A model large beside its data (the F-16's 2,893 parameters on 98,304
residuals) has each step solved by a Cholesky factorisation instead (see
``solver``): the eigendecomposition would cost more than a quarter of the
Gram matrix itself.

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
from scipy.linalg import LinAlgError, cho_factor, cho_solve

from ..utils.threads import symmetric_threads_for

__all__ = ["LMResult", "levenberg_marquardt", "lm_step_basis"]


@dataclass
class LMResult:
    theta: np.ndarray
    cost: float
    n_iter: int
    history: list = field(default_factory=list)  # (iteration, cost, lambda)


def _scaled_gram(G):
    """Column scales of the Jacobian (its columns' norms, 1 for a zero
    column) and the Gram matrix of the scaled columns."""
    scale = np.sqrt(np.diag(G))
    scale[scale == 0] = 1.0
    return scale, G / np.outer(scale, scale)


def lm_step_basis(G, n_drop):
    """Column scales, kept singular values and right singular vectors of the
    column-scaled Jacobian, from its Gram matrix ``G = J^T J``.

    Returns ``scale`` (n_params,), ``S`` (k,) descending, ``V`` (n_params, k).
    """
    scale, Gs = _scaled_gram(G)
    w, V = np.linalg.eigh(Gs)
    w, V = w[::-1], V[:, ::-1]
    keep = max(w.size - n_drop, 1)
    # Below eps * largest, an eigenvalue of the Gram matrix is rounding noise.
    keep = max(min(keep, int(np.sum(w > w[0] * w.size * np.finfo(float).eps))), 1)
    return scale, np.sqrt(np.maximum(w[:keep], 0.0)), V[:, :keep]


class _EigenSteps:
    """Damped steps in the kept right singular vectors of the scaled
    Jacobian (the toolbox's way): one eigendecomposition per iteration,
    then each trial damping costs two matrix-vector products."""

    def __init__(self, G, g, n_drop):
        self.scale, self.S, self.V = lm_step_basis(G, n_drop)
        self.Vg = self.V.T @ (g / self.scale)
        self.largest = float(self.S[0] ** 2)

    def step(self, mu):
        """The step -V diag(1 / (S^2 + mu)) V^T J^T e, unscaled (to subtract)."""
        return (self.V @ (self.Vg / (self.S**2 + mu))) / self.scale

    def predicted_fall(self, mu):
        """The cost's fall the linearised model predicts for step(mu)."""
        S2 = self.S**2
        return float(np.sum(self.Vg**2 * (S2 + 2 * mu) / (S2 + mu) ** 2))


class _CholeskySteps:
    """The same damped step from a Cholesky factorisation of the scaled
    Gram matrix plus mu I, one per trial damping: p^3 / 3 flops against
    the eigendecomposition's ~15 p^3 (measured), for models whose Gram
    matrix is large beside the data. No direction is dropped: along an
    exact null direction the gradient is zero, so the step has no
    component there either, and the damping bounds it in the nearly null
    ones."""

    def __init__(self, G, g):
        self.scale, self.Gs = _scaled_gram(G)
        self.gs = g / self.scale
        self.largest = _largest_eigenvalue(self.Gs)
        self._last = None

    def step(self, mu):
        """As _EigenSteps.step; None when Gs + mu I is not numerically
        positive definite."""
        damped = self.Gs + mu * np.eye(self.gs.size)
        try:
            with symmetric_threads_for(self.gs.size):
                factor = cho_factor(damped, lower=True, overwrite_a=True, check_finite=False)
        except LinAlgError:
            return None
        s = cho_solve(factor, self.gs, check_finite=False)
        self._last = (mu, s)
        return s / self.scale

    def predicted_fall(self, mu):
        """2 s'g - s'Gs s, which is s'g + mu s's for s = (Gs + mu I)^-1 g."""
        last_mu, s = self._last
        assert last_mu == mu
        return float(s @ self.gs + mu * (s @ s))


def _largest_eigenvalue(Gs, n_iter=30):
    """The largest eigenvalue of a symmetric positive semi-definite matrix,
    by power iteration (it sets the first damping and the stopping damping,
    for which a few digits suffice)."""
    v = np.full(Gs.shape[0], 1 / np.sqrt(Gs.shape[0]))
    value = 1.0
    for _ in range(n_iter):
        w = Gs @ v
        value = float(np.linalg.norm(w))
        if value == 0.0:
            return 1.0
        v = w / value
    return float(v @ Gs @ v)


#: solver="auto" keeps the eigendecomposition for at most this many
#: parameters (cheap outright: 40 ms at 500 on 2 cores) ...
EIGH_MAX_PARAMS = 512
#: ... or while the residual has this many rows per parameter: it costs
#: about 15 p^3 flops (numpy/OpenBLAS, measured on 2 cores) against the
#: Gram matrix's n_rows p^2, so under a quarter of it.
EIGH_ROWS_PER_PARAM = 60


def _steps(G, g, n_drop, solver, n_rows):
    """The step solver for this iteration (see ``solver`` of
    levenberg_marquardt)."""
    if solver == "auto":
        p = g.size
        solver = "eigh" if p <= EIGH_MAX_PARAMS or EIGH_ROWS_PER_PARAM * p <= n_rows else "cholesky"
    return _EigenSteps(G, g, n_drop) if solver == "eigh" else _CholeskySteps(G, g)


def levenberg_marquardt(
    residual, normal_equations, theta0, *, n_drop=0, max_iter=100, tol=1e-10,
    max_lambda=1e12, callback=None, basis=None, damping="nielsen", solver="auto",
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
    basis : ndarray of shape (n_params, k) or None
        Of full column rank: each step is ``basis @ phi`` with ``phi``
        solved from the Jacobian ``J @ basis``; with fewer columns than
        parameters (``k < n_params``), the steps stay in its range (held
        parameters). None: the identity.
    damping : {"nielsen", "toolbox"}, default="nielsen"
        How the damping changes between steps: Nielsen's rule (see the
        module), or the PNLSS toolbox's (lambda halved on success,
        multiplied by 10 on failure), kept to compare with it.
    solver : {"auto", "eigh", "cholesky"}, default="auto"
        How each damped step is solved. "eigh": in the right singular
        vectors of the scaled Jacobian, the ``n_drop`` smallest dropped
        (one eigendecomposition per iteration). "cholesky": a Cholesky
        factorisation of the damped scaled Gram matrix per trial damping,
        nothing dropped (the gradient has no component along an exact
        null direction, and the damping bounds the nearly null ones),
        about 40 times cheaper for a large model. "auto": "eigh" for at
        most :data:`EIGH_MAX_PARAMS` parameters or while the residual has
        :data:`EIGH_ROWS_PER_PARAM` rows per parameter, "cholesky" beyond.

    Returns
    -------
    LMResult
    """
    if damping not in ("nielsen", "toolbox"):
        raise ValueError(f"damping must be 'nielsen' or 'toolbox'; got {damping!r}.")
    if solver not in ("auto", "eigh", "cholesky"):
        raise ValueError(f"solver must be 'auto', 'eigh' or 'cholesky'; got {solver!r}.")
    theta = np.array(theta0, dtype=float)
    e = residual(theta)
    if e is None or not np.all(np.isfinite(e)):
        raise ValueError("The starting model diverges on the training data; cannot optimise from it.")
    cost = float(e @ e)
    history = [(0, cost, np.nan)]
    mu, nu = None, 2.0  # damping (lambda^2) and its growth at the next failure
    it = 0
    for it in range(1, max_iter + 1):
        G, g = normal_equations(theta)
        if basis is not None:
            G, g = basis.T @ G @ basis, basis.T @ g
        steps = _steps(G, g, n_drop, solver, e.size)
        if mu is None:
            mu = steps.largest
        improved = False
        while mu <= max_lambda**2 * steps.largest:
            step = steps.step(mu)
            if step is None:  # the damped Gram matrix is not positive definite in floating point
                steps = _EigenSteps(G, g, n_drop)
                continue
            trial = theta - (step if basis is None else basis @ step)
            e_new = residual(trial)
            if e_new is not None and np.all(np.isfinite(e_new)):
                cost_new = float(e_new @ e_new)
                if cost_new < cost:
                    rho = (cost - cost_new) / steps.predicted_fall(mu)
                    rel = (cost - cost_new) / cost
                    theta, e, cost = trial, e_new, cost_new
                    mu *= max(1 / 3, 1 - (2 * rho - 1) ** 3) if damping == "nielsen" else 1 / 4
                    nu = 2.0
                    improved = True
                    break
            mu *= nu if damping == "nielsen" else 100.0
            nu *= 2
        history.append((it, cost, np.sqrt(mu)))
        if callback is not None:
            callback(it, theta, cost, np.sqrt(mu))
        if not improved or rel < tol:
            break
    return LMResult(theta=theta, cost=cost, n_iter=it, history=history)
