"""Compiled time recursions of the PNLSS model.

    x(t+1) = A x + B u + E zeta(s),   y = C x + D u + F eta(s),   s = [x; u]

Parameters are ordered theta = [A, B, E | C, D, F] (row-major blocks): the
first group moves the state, the second only the output. The Jacobian of the
simulated output comes from the sensitivity recursion
dx/dtheta(t+1) = (A + E dzeta/dx) dx/dtheta(t) + direct term,
one pass over time for all parameters at once.
"""
import numba
import numpy as np

# States beyond this (in normalised units, where they are of order one) mean
# the simulation diverged: stop and report instead of overflowing.
DIVERGENCE_BOUND = 1e6


@numba.njit(cache=True, nogil=True, inline="always")
def _monomials(s, exps, out, dout, pw):
    """Monomials and their derivatives with respect to each variable."""
    n_terms, n_vars = exps.shape
    max_deg = pw.shape[1] - 1
    for v in range(n_vars):
        pw[v, 0] = 1.0
        for e in range(1, max_deg + 1):
            pw[v, e] = pw[v, e - 1] * s[v]
    for j in range(n_terms):
        val = 1.0
        for v in range(n_vars):
            val *= pw[v, exps[j, v]]
        out[j] = val
        for v in range(n_vars):
            e = exps[j, v]
            if e == 0:
                dout[j, v] = 0.0
            else:
                d = e * pw[v, e - 1]
                for w in range(n_vars):
                    if w != v:
                        d *= pw[w, exps[j, w]]
                dout[j, v] = d


@numba.njit(cache=True, nogil=True)
def _workspace(exE, exF, nv):
    """Scratch arrays (powers, zeta, dzeta, eta, deta, s) for one pass."""
    max_deg = 1
    for j in range(exE.shape[0]):
        max_deg = max(max_deg, exE[j].sum())
    for j in range(exF.shape[0]):
        max_deg = max(max_deg, exF[j].sum())
    return (
        np.empty((nv, max_deg + 1)),
        np.empty(exE.shape[0]),
        np.empty((exE.shape[0], nv)),
        np.empty(exF.shape[0]),
        np.empty((exF.shape[0], nv)),
        np.empty(nv),
    )


@numba.njit(cache=True, nogil=True, inline="always")
def _nonlinear_terms(x, u, exE, exF, ws):
    """zeta, eta and their derivatives at s = [x; u], into the workspace."""
    pw, zeta, dzeta, eta, deta, s = ws
    n = x.shape[0]
    for i in range(n):
        s[i] = x[i]
    for i in range(u.shape[0]):
        s[n + i] = u[i]
    _monomials(s, exE, zeta, dzeta, pw)
    _monomials(s, exF, eta, deta, pw)


@numba.njit(cache=True, nogil=True, inline="always")
def _linearised(L, W, dterms, n, out):
    """out = L + W dterms[:, :n]: the local linear map of x (A + E dzeta/dx,
    or C + F deta/dx)."""
    for i in range(L.shape[0]):
        for k in range(n):
            acc = L[i, k]
            for j in range(W.shape[1]):
                acc += W[i, j] * dterms[j, k]
            out[i, k] = acc


@numba.njit(cache=True, nogil=True)
def pnlss_simulate(A, B, C, D, E, F, exE, exF, U, x0):
    """Simulate; returns (Y, X, n_ok, x_end). n_ok < len(U) means the state
    left the range (divergence) after sample n_ok - 1."""
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    ws = _workspace(exE, exF, n + m)
    zeta, eta = ws[1], ws[3]
    Y = np.zeros((N, p))
    X = np.zeros((N, n))
    x = x0.copy()
    for t in range(N):
        _nonlinear_terms(x, U[t], exE, exF, ws)
        X[t] = x
        Y[t] = C @ x + D @ U[t] + F @ eta
        x = A @ x + B @ U[t] + E @ zeta
        for i in range(n):
            if not np.abs(x[i]) < DIVERGENCE_BOUND:  # also catches NaN
                return Y, X, t + 1, x
    return Y, X, N, x


@numba.njit(cache=True, nogil=True)
def pnlss_jacobian(A, B, C, D, E, F, exE, exF, U, x0, n_skip, J):
    """Output sensitivities dy(t)/dtheta for t >= n_skip, written to
    J[(t - n_skip), :, :] (shape (N - n_skip, p, n_theta))."""
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    nE = exE.shape[0]
    nF = exF.shape[0]
    nv = n + m
    n_sx = n * n + n * m + n * nE  # parameters that move the state
    oA, oB, oE = 0, n * n, n * n + n * m
    oC = n_sx
    oD = oC + p * n
    oF = oD + p * m
    ws = _workspace(exE, exF, nv)
    zeta, dzeta, eta, deta = ws[1], ws[2], ws[3], ws[4]
    Sx = np.zeros((n, n_sx))
    Sx_new = np.empty((n, n_sx))
    Ax = np.empty((n, n))  # A + E dzeta/dx
    Cx = np.empty((p, n))  # C + F deta/dx
    x = x0.copy()
    for t in range(N):
        _nonlinear_terms(x, U[t], exE, exF, ws)
        _linearised(A, E, dzeta, n, Ax)
        if t >= n_skip:
            r = t - n_skip
            _linearised(C, F, deta, n, Cx)
            for a in range(p):
                for q in range(n_sx):
                    acc = 0.0
                    for k in range(n):
                        acc += Cx[a, k] * Sx[k, q]
                    J[r, a, q] = acc
                for k in range(n):
                    J[r, a, oC + a * n + k] = x[k]
                for k in range(m):
                    J[r, a, oD + a * m + k] = U[t, k]
                for k in range(nF):
                    J[r, a, oF + a * nF + k] = eta[k]
        # Sensitivity of the next state.
        for i in range(n):
            for q in range(n_sx):
                acc = 0.0
                for k in range(n):
                    acc += Ax[i, k] * Sx[k, q]
                Sx_new[i, q] = acc
            for k in range(n):
                Sx_new[i, oA + i * n + k] += x[k]
            for k in range(m):
                Sx_new[i, oB + i * m + k] += U[t, k]
            for k in range(nE):
                Sx_new[i, oE + i * nE + k] += zeta[k]
        Sx[:, :] = Sx_new
        x = A @ x + B @ U[t] + E @ zeta
