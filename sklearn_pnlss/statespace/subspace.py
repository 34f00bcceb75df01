"""Frequency-domain subspace identification of a linear state-space model
from FRF data, weighted by the FRF variance, and its refinement by a weighted
nonlinear least-squares fit.

References: McKelvey, Akcay & Ljung (1996), "Subspace-based multivariable
system identification from frequency response data", IEEE TAC 41(7);
Pintelon (2002), "Frequency-domain subspace system identification using
non-parametric noise models", Automatica 38(8).
"""
import numpy as np
from scipy.linalg import qr, sqrtm, svd

from .levenberg_marquardt import levenberg_marquardt
from .linear import is_stable, stabilize

__all__ = ["fd_subspace", "fd_refine", "frf_weights"]


def frf_weights(G, var):
    """Per-line weights ``1/sigma`` from FRF variances (K, p, m).

    Residuals weighted this way have unit variance. Lines without a usable variance (zero, NaN) get the median weight so a
    noiseless simulation does not produce infinite weights.
    """
    K = G.shape[0]
    # Without a variance, weigh relative to the FRF level so that residuals
    # are of order one and the solver's tolerances mean something.
    unweighted = np.ones(K) / np.sqrt(np.mean(np.abs(G) ** 2))
    if var is None:
        return unweighted
    sigma2 = np.mean(np.asarray(var, dtype=float).reshape(K, -1), axis=1)
    good = np.isfinite(sigma2) & (sigma2 > 0)
    if not np.any(good):
        return unweighted
    floor = np.median(sigma2[good]) * 1e-6
    sigma2 = np.where(good, np.maximum(sigma2, floor), np.median(sigma2[good]))
    return 1.0 / np.sqrt(sigma2)


def _estimate_bd(A, C, G, z, w, estimate_d=True):
    """Weighted linear least squares for B and D given A and C."""
    K, p, m = G.shape
    n = A.shape[0]
    # C (zI - A)^-1, shape (K, p, n)
    CP = np.linalg.solve(
        (z[:, None, None] * np.eye(n) - A).transpose(0, 2, 1),
        np.broadcast_to(C.T, (K, n, p)),
    ).transpose(0, 2, 1)
    # vec(CP B + D) = (I_m kron CP) vec(B) + (I_m kron I_p) vec(D)
    blocks = [np.kron(np.eye(m), CP[k]) for k in range(K)]  # (p m, n m)
    M = np.stack(blocks)
    if estimate_d:
        M = np.concatenate([M, np.broadcast_to(np.eye(p * m), (K, p * m, p * m))], axis=2)
    rhs = G.transpose(0, 2, 1).reshape(K, p * m)  # column-major vec per line
    M = M * w[:, None, None]
    rhs = rhs * w[:, None]
    Mr = np.concatenate([M.real.reshape(-1, M.shape[2]), M.imag.reshape(-1, M.shape[2])])
    rr = np.concatenate([rhs.real.ravel(), rhs.imag.ravel()])
    theta = np.linalg.lstsq(Mr, rr, rcond=None)[0]
    B = theta[: n * m].reshape(m, n).T
    D = theta[n * m :].reshape(m, p).T if estimate_d else np.zeros((p, m))
    return B, D


def fd_subspace(G, z, n_states, *, var=None, q=None, estimate_d=True):
    """Weighted frequency-domain subspace identification.

    Parameters
    ----------
    G : ndarray of shape (K, p, m), complex
        Frequency response at the points ``z``.
    z : ndarray of shape (K,), complex
        Points on the unit circle, ``exp(j 2 pi f / fs)``.
    n_states : int
        Model order.
    var : ndarray of shape (K, p, m), default=None
        Variance of ``G``; lines are weighted by ``1/sigma``.
    q : int, default=None
        Block rows of the extended observability matrix (> n_states);
        ``max(n_states + 1, 2 n_states)`` when None.
    estimate_d : bool, default=True
        Estimate the direct feedthrough D (else D = 0).

    Returns
    -------
    A, B, C, D : ndarray
        A stable discrete-time model (unstable poles are reflected).
    """
    G = np.asarray(G, dtype=complex)
    K, p, m = G.shape
    n = int(n_states)
    if q is None:
        q = max(n + 1, 2 * n)
    if q <= n:
        raise ValueError(f"q must exceed n_states={n}; got q={q}.")
    if K * m < q * m + n:
        raise ValueError(
            f"Too few frequency lines ({K}) for a model of order {n}; "
            "excite more lines or lower n_states."
        )
    w = frf_weights(G, var)
    powers = z[None, :] ** np.arange(q)[:, None]  # (q, K)
    # Columns of the data matrices, one (q p x m) / (q m x m) block per line.
    Gcal = np.einsum("ik,kab->iakb", powers, G).reshape(q * p, K * m)
    Wcal = np.einsum("ik,ab->iakb", powers, np.eye(m)).reshape(q * m, K * m)
    col_w = np.repeat(w, m)
    Gcal = Gcal * col_w
    Wcal = Wcal * col_w
    Gr = np.concatenate([Gcal.real, Gcal.imag], axis=1)
    Wr = np.concatenate([Wcal.real, Wcal.imag], axis=1)
    # Remove the input part: LQ of [W; G] via QR of its transpose.
    R = qr(np.concatenate([Wr, Gr]).T, mode="r")[0].T
    R22 = R[q * m :, q * m :]
    # Weighted lines carry unit-variance noise, which enters the rows through
    # the powers of z: whiten with that row covariance before the SVD.
    CN = np.real(powers @ powers.conj().T) / K
    CN = np.kron(CN, np.eye(p))
    CN_half = np.real(sqrtm(CN))
    U_svd = svd(np.linalg.solve(CN_half, R22), full_matrices=False)[0]
    Obs = CN_half @ U_svd[:, :n]
    C = Obs[:p]
    A = np.linalg.lstsq(Obs[:-p], Obs[p:], rcond=None)[0]
    if not is_stable(A):
        A = stabilize(A)
    B, D = _estimate_bd(A, C, G, z, w, estimate_d)
    return A, B, C, D


def _pack(A, B, C, D, estimate_d):
    parts = [A.ravel(), B.ravel(), C.ravel()]
    if estimate_d:
        parts.append(D.ravel())
    return np.concatenate(parts)


def _unpack(theta, n, m, p, estimate_d):
    i, j, k = n * n, n * n + n * m, n * n + n * m + p * n
    A = theta[:i].reshape(n, n)
    B = theta[i:j].reshape(n, m)
    C = theta[j:k].reshape(p, n)
    D = theta[k : k + p * m].reshape(p, m) if estimate_d else np.zeros((p, m))
    return A, B, C, D


def fd_refine(A, B, C, D, G, z, *, var=None, estimate_d=True, max_iter=100):
    """Refine a linear model by weighted least squares on the FRF.

    Minimises ``sum_k |G_model(z_k) - G_k|^2 / sigma_k^2`` over A, B, C, D by
    the library's Levenberg-Marquardt (Jacobian columns scaled to unit rms,
    the ``n^2`` smallest singular values dropped from each step). The
    dropped directions are those of the state basis, which leave the FRF
    unchanged; a solver that keeps them (a trust region on all entries)
    drifts along them by amounts set by rounding, so the basis of its result,
    and every nonlinear fit started from it, changed when the data were
    rescaled. With them dropped the steps are continuous in the data and
    rescaling the input or output only rescales B and D. LM stops when a
    step lowers the cost by less than 1e-8 of it, or after ``max_iter``
    Jacobian evaluations. A refined model that is unstable or fits worse is
    discarded and the start returned.

    Returns
    -------
    A, B, C, D : ndarray
    """
    G = np.asarray(G, dtype=complex)
    K, p, m = G.shape
    n = A.shape[0]
    w = frf_weights(G, var)
    eye = np.eye(n)

    def residual_and_jac(theta):
        A_, B_, C_, D_ = _unpack(theta, n, m, p, estimate_d)
        res = z[:, None, None] * eye - A_
        PB = np.linalg.solve(res, np.broadcast_to(B_, (K, n, m)))  # (K,n,m)
        CP = np.linalg.solve(res.transpose(0, 2, 1), np.broadcast_to(C_.T, (K, n, p))).transpose(0, 2, 1)
        E = (D_[None] + C_[None] @ PB - G) * w[:, None, None]  # (K,p,m)
        # dG_ab/dA_ij = CP_ai PB_jb ; dG_ab/dB_ij = CP_ai d_jb ; dG_ab/dC_ij = d_ai PB_jb
        JA = np.einsum("kai,kjb->kabij", CP, PB).reshape(K, p, m, n * n)
        JB = np.einsum("kai,jb->kabij", CP, np.eye(m)).reshape(K, p, m, n * m)
        JC = np.einsum("ai,kjb->kabij", np.eye(p), PB).reshape(K, p, m, p * n)
        blocks = [JA, JB, JC]
        if estimate_d:
            JD = np.broadcast_to(
                np.einsum("ai,bj->abij", np.eye(p), np.eye(m)).reshape(p, m, p * m),
                (K, p, m, p * m),
            )
            blocks.append(JD)
        J = np.concatenate(blocks, axis=3) * w[:, None, None, None]
        J = J.reshape(K * p * m, -1)
        E = E.ravel()
        return np.concatenate([E.real, E.imag]), np.concatenate([J.real, J.imag])

    def residual(theta):
        with np.errstate(all="ignore"):
            try:
                return residual_and_jac(theta)[0]
            except np.linalg.LinAlgError:  # a pole exactly on an excited line
                return None

    def normal_equations(theta):
        e, J = residual_and_jac(theta)
        return J.T @ J, J.T @ e

    theta0 = _pack(A, B, C, D, estimate_d)
    e0 = residual(theta0)
    if e0 is None or not np.all(np.isfinite(e0)):
        return A, B, C, D
    result = levenberg_marquardt(residual, normal_equations, theta0, n_drop=n * n, max_iter=max_iter, tol=1e-8)
    A1, B1, C1, D1 = _unpack(result.theta, n, m, p, estimate_d)
    if not is_stable(A1) or result.cost > e0 @ e0:
        return A, B, C, D
    return A1, B1, C1, D1
