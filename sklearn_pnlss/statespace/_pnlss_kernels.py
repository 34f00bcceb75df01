"""Compiled time recursions of the PNLSS model.

    x(t+1) = A x + B u + E zeta(s),   y = C x + D u + F eta(s),   s = [x; u]

Parameters are ordered theta = [A, B, E | C, D, F] (row-major blocks): the
first group moves the state, the second only the output. The Jacobian of the
simulated output comes from the sensitivity recursion
dx/dtheta(t+1) = (A + E dzeta/dx) dx/dtheta(t) + direct term,
one pass over time for all parameters at once.

The monomials are evaluated at ``s`` held inside its trusted box
``[lo, hi]`` (the range each variable covered in training): outside it a
variable is held at the edge, so ``zeta`` and ``eta`` are bounded and a
stable ``A`` gives a bounded state for every bounded input; a held state has
no influence on the monomials (zero derivative). An infinite box is the plain
polynomial. The box is a constant of the model, not a parameter, so the
Jacobian stays exact.

The loops are written out (no ``@`` on small arrays): numba's matrix
products allocate at every sample, which cost more than the arithmetic. The
one product that is large, the sensitivities carried to the next sample
(n x n times n x n_sx), goes to BLAS when it is large enough to gain.
"""
import numba
import numpy as np

# States beyond this (in normalised units, where they are of order one) mean
# the simulation diverged: stop and report instead of overflowing.
DIVERGENCE_BOUND = 1e6

_jit = numba.njit(cache=True, nogil=True, inline="always")

# Below this many multiply-adds in one matrix product, written-out loops beat
# a BLAS call, whose fixed cost is of the order of a microsecond (measured on
# the sensitivities carried to the next sample, n x n times n x n_sx:
# Bouc-Wen, n = 3, 60 columns, loops faster; F-16, n = 10, 2,860 columns,
# BLAS 24 GMAC/s against 6 with the loops).
_BLAS_FROM = 4096


@_jit
def _powers(s, pw):
    """pw[v, e] = s[v] ** e for e up to the largest degree."""
    for v in range(s.shape[0]):
        pw[v, 0] = 1.0
        for e in range(1, pw.shape[1]):
            pw[v, e] = pw[v, e - 1] * s[v]


@_jit
def _monomial_values(exps, pw, out):
    for j in range(exps.shape[0]):
        val = 1.0
        for v in range(exps.shape[1]):
            val *= pw[v, exps[j, v]]
        out[j] = val


@_jit
def _state_derivatives(exps, pw, n, dout):
    """dout[j, k] = d monomial_j / d x_k for the n states (the inputs are
    given, so their derivatives are never needed)."""
    n_vars = exps.shape[1]
    for j in range(exps.shape[0]):
        for k in range(n):
            e = exps[j, k]
            if e == 0:
                dout[j, k] = 0.0
                continue
            d = e * pw[k, e - 1]
            for w in range(n_vars):
                if w != k:
                    d *= pw[w, exps[j, w]]
            dout[j, k] = d


@numba.njit(cache=True, nogil=True)
def _max_degree(exE, exF):
    deg = 1
    for j in range(exE.shape[0]):
        deg = max(deg, exE[j].sum())
    for j in range(exF.shape[0]):
        deg = max(deg, exF[j].sum())
    return deg


@_jit
def _stack(x, u, s):
    n = x.shape[0]
    for i in range(n):
        s[i] = x[i]
    for i in range(u.shape[0]):
        s[n + i] = u[i]


@_jit
def _hold(s, lo, hi, inside):
    """s clipped to [lo, hi] in place; ``inside[v]`` False where it was."""
    for v in range(s.shape[0]):
        c = min(max(s[v], lo[v]), hi[v])
        inside[v] = c == s[v]
        s[v] = c


@_jit
def _zero_held(dterms, inside):
    """No dependence of the monomials on a state held at its edge."""
    for k in range(dterms.shape[1]):
        if not inside[k]:
            for j in range(dterms.shape[0]):
                dterms[j, k] = 0.0


@_jit
def _affine(M, v, N, w, P, z, out):
    """out = M v + N w + P z (the state or output update)."""
    for i in range(out.shape[0]):
        acc = 0.0
        for k in range(v.shape[0]):
            acc += M[i, k] * v[k]
        for k in range(w.shape[0]):
            acc += N[i, k] * w[k]
        for k in range(z.shape[0]):
            acc += P[i, k] * z[k]
        out[i] = acc


@_jit
def _linearised(L, W, dterms, out):
    """out = L + W dterms: the local linear map of x (A + E dzeta/dx, or
    C + F deta/dx)."""
    if L.shape[0] * W.shape[1] * L.shape[1] >= _BLAS_FROM:
        np.dot(W, dterms, out)
        for i in range(L.shape[0]):
            for k in range(L.shape[1]):
                out[i, k] += L[i, k]
        return
    for i in range(L.shape[0]):
        for k in range(L.shape[1]):
            acc = L[i, k]
            for j in range(W.shape[1]):
                acc += W[i, j] * dterms[j, k]
            out[i, k] = acc


@_jit
def _propagate(M, S, out):
    """out = M S, written out."""
    for i in range(M.shape[0]):
        for q in range(S.shape[1]):
            out[i, q] = 0.0
        for k in range(M.shape[1]):
            c = M[i, k]
            for q in range(S.shape[1]):
                out[i, q] += c * S[k, q]


@_jit
def _carry(M, S, out):
    """out = M S (sensitivities through the local linear map)."""
    if M.shape[0] * M.shape[1] * S.shape[1] < _BLAS_FROM:
        _propagate(M, S, out)
    else:
        np.dot(M, S, out)


@numba.njit(cache=True, nogil=True)
def pnlss_simulate(A, B, C, D, E, F, exE, exF, lo, hi, U, x0):
    """Simulate; returns (Y, X, n_ok, x_end). n_ok < len(U) means the state
    left the range (divergence) after sample n_ok - 1."""
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    pw = np.empty((n + m, _max_degree(exE, exF) + 1))
    s = np.empty(n + m)
    inside = np.empty(n + m, dtype=np.bool_)
    zeta = np.empty(exE.shape[0])
    eta = np.empty(exF.shape[0])
    Y = np.empty((N, p))
    X = np.empty((N, n))
    x = x0.copy()
    x_next = np.empty(n)
    for t in range(N):
        _stack(x, U[t], s)
        _hold(s, lo, hi, inside)
        _powers(s, pw)
        _monomial_values(exE, pw, zeta)
        _monomial_values(exF, pw, eta)
        X[t] = x
        _affine(C, x, D, U[t], F, eta, Y[t])
        _affine(A, x, B, U[t], E, zeta, x_next)
        x, x_next = x_next, x
        for i in range(n):
            if not np.abs(x[i]) < DIVERGENCE_BOUND:  # also catches NaN
                return Y, X, t + 1, x
    return Y, X, N, x


@numba.njit(cache=True, nogil=True)
def pnlss_jacobian(A, B, C, D, E, F, exE, exF, lo, hi, U, x, Sx, n_skip, J):
    """Output sensitivities dy(t)/dtheta for t >= n_skip, written to
    J[(t - n_skip), :, :] (shape (N - n_skip, p, n_theta)).

    Resumable, so that a long signal can be taken in blocks of samples
    (memory): ``x`` (n,) is the state and ``Sx`` (n, n_sx) its sensitivity
    to the parameters that move the state at the first sample of ``U``; both
    are advanced in place to the sample after the last. ``Sx`` may carry
    more columns than the n_sx parameters: sensitivities to a start state,
    propagated without direct terms and written to the last columns of
    ``J`` (after the parameters'; see ``StateSpaceModel.jacobian_blocks``).

    The sensitivities are carried through the local linear map by a matrix
    product (BLAS): it is the bulk of the arithmetic, n^2 n_sx per sample,
    and runs at several times the speed of written-out loops once n_sx is in
    the hundreds.
    """
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    nE = exE.shape[0]
    nF = exF.shape[0]
    n_sx = n * n + n * m + n * nE  # parameters that move the state
    n_cols = Sx.shape[1]  # and the start-state columns after them
    n_par = J.shape[2] - (n_cols - n_sx)
    oA, oB, oE = 0, n * n, n * n + n * m
    oC = n_sx
    oD = oC + p * n
    oF = oD + p * m
    pw = np.empty((n + m, _max_degree(exE, exF) + 1))
    s = np.empty(n + m)
    inside = np.empty(n + m, dtype=np.bool_)
    zeta = np.empty(nE)
    dzeta = np.empty((nE, n))
    eta = np.empty(nF)
    deta = np.empty((nF, n))
    S = Sx.copy()  # contiguous work copies, swapped every sample
    S_next = np.empty((n, n_cols))
    Jx = np.empty((p, n_cols))
    Ax = np.empty((n, n))  # A + E dzeta/dx
    Cx = np.empty((p, n))  # C + F deta/dx
    x_now = x.copy()
    x_next = np.empty(n)
    for t in range(N):
        u = U[t]
        _stack(x_now, u, s)
        _hold(s, lo, hi, inside)
        _powers(s, pw)
        _monomial_values(exE, pw, zeta)
        _state_derivatives(exE, pw, n, dzeta)
        _zero_held(dzeta, inside)
        _linearised(A, E, dzeta, Ax)
        if t >= n_skip:
            _monomial_values(exF, pw, eta)
            _state_derivatives(exF, pw, n, deta)
            _zero_held(deta, inside)
            _linearised(C, F, deta, Cx)
            _carry(Cx, S, Jx)
            Jt = J[t - n_skip]
            for a in range(p):
                for q in range(n_sx):
                    Jt[a, q] = Jx[a, q]
                for q in range(n_sx, n_par):
                    Jt[a, q] = 0.0
                for q in range(n_sx, n_cols):
                    Jt[a, n_par + q - n_sx] = Jx[a, q]
                for k in range(n):
                    Jt[a, oC + a * n + k] = x_now[k]
                for k in range(m):
                    Jt[a, oD + a * m + k] = u[k]
                for k in range(nF):
                    Jt[a, oF + a * nF + k] = eta[k]
        # Sensitivity of the next state: the propagated part, then the
        # direct dependence of row i on its own parameters.
        _carry(Ax, S, S_next)
        for i in range(n):
            for k in range(n):
                S_next[i, oA + i * n + k] += x_now[k]
            for k in range(m):
                S_next[i, oB + i * m + k] += u[k]
            for k in range(nE):
                S_next[i, oE + i * nE + k] += zeta[k]
        S, S_next = S_next, S
        _affine(A, x_now, B, u, E, zeta, x_next)
        x_now, x_next = x_next, x_now
    x[:] = x_now
    Sx[:, :] = S
