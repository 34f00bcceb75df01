"""Compiled time recursions of the decoupled polynomial state-space model.

    z = V^T s,   s = [x; u],   g_l(z_l) = sum_k G[l, k] z_l ** (k + 1)
    x(t+1) = A x + B u + Wx g(z),   y = C x + D u + Wy g(z)

or, signed powers, g_l(z_l) = sum_k G[l, k] z_l |z_l| ** k (odd functions),
or, spline branches, g_l(z_l) = sum_k G[l, k] (B_k(z_l) - B_k(0)) with
uniform cubic B-splines B_k (see :mod:`.splines`).

Parameters are ordered theta = [A, B, Wx, V, G | C, D (, Wy)] (row-major
blocks): the first group moves the state, the second only the output; ``Wy``
is a parameter only when the output branches are (``out_branch_params``).
``V`` and ``G`` move the state and, through ``Wy g(z)``, also enter the
output directly.

The Jacobian of the simulated output comes from the sensitivity recursion

    dx/dtheta(t+1) = (A + Wx diag(g'(z)) Vx^T) dx/dtheta(t) + direct term
    dy/dtheta(t)   = (C + Wy diag(g'(z)) Vx^T) dx/dtheta(t) + direct term

(``Vx``: the rows of ``V`` that multiply the states), one pass over time for
all parameters at once. As in :mod:`._pnlss_kernels`, the loops are written
out (no ``@`` on small arrays, which would allocate at every sample) and the
powers ``z ** k`` are built by repeated multiplication (no ``pow`` calls).

Polynomial branches pass ``knots=None`` (and ``B0=None``): numba compiles
the kernels once per argument type and drops the spline code from the
polynomial ones. Chosen at run time by a flag instead, the spline code
alone (never run) made the simulation of a 3-branch, degree-6 model 4.6
times slower (170 against 37 ns a sample) and its Jacobian 1.5 times.

The small inline helpers (``_affine`` ...) are defined here again rather than
imported from :mod:`._pnlss_kernels`: numba's on-disk cache checks only the
source file of the cached function, so a helper changed in another module
would leave a stale compiled kernel behind.
"""
import numba
import numpy as np

from ._pnlss_kernels import DIVERGENCE_BOUND

_jit = numba.njit(cache=True, nogil=True, inline="always")


@_jit
def _stack(x, u, s):
    n = x.shape[0]
    for i in range(n):
        s[i] = x[i]
    for i in range(u.shape[0]):
        s[n + i] = u[i]


@_jit
def _polynomial_at(G, b, signed, zc, zp, dzp):
    """g_b(zc), g_b'(zc); zp[b, k] = z**(k+1) (``signed``: z |z|**k),
    dzp[k] its z-derivative."""
    val = 0.0
    der = 0.0
    # signed: the even powers z**(k+1) turn into z |z|**k = sign(z) z**(k+1)
    sign = -1.0 if signed and zc < 0.0 else 1.0
    zk = 1.0  # zc ** k
    for k in range(G.shape[1]):
        f = sign if k % 2 == 1 else 1.0
        dzp[k] = (k + 1) * zk * f
        der += G[b, k] * dzp[k]
        zk *= zc
        zp[b, k] = zk * f
        val += G[b, k] * zp[b, k]
    return val, der


@_jit
def _spline_at(G, b, knots, B0, zc, zp, dzp):
    """The spline branch g_b(zc) = sum_k G[b, k] (B_k(zc) - B_k(0)), uniform
    cubic B-splines B_k with first knot knots[b, 0] and spacing knots[b, 1],
    continued along its edge tangent outside its knots; its derivative, and
    zp[b, k] = B_k(zc) - B_k(0), dzp[k] = B_k'(zc). Only four B_k are
    non-zero at a point: the cost of a branch does not grow with its
    knots."""
    d = G.shape[1]
    h = knots[b, 1]
    n_int = d - 3
    te = min(max((zc - knots[b, 0]) / h, 0.0), float(n_int))  # in knot spacings, inside the knots
    i = min(int(te), n_int - 1)
    u = te - i
    dz = zc - (knots[b, 0] + te * h)  # beyond the knots: the tangent's run
    for k in range(d):
        zp[b, k] = -B0[b, k]
        dzp[k] = 0.0
    v = 1.0 - u
    w0, w1, w2, w3 = v * v * v / 6, (3 * u * u * u - 6 * u * u + 4) / 6, (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6, u * u * u / 6
    d0, d1, d2, d3 = -v * v / (2 * h), (3 * u * u - 4 * u) / (2 * h), (-3 * u * u + 2 * u + 1) / (2 * h), u * u / (2 * h)
    zp[b, i] += w0 + d0 * dz
    zp[b, i + 1] += w1 + d1 * dz
    zp[b, i + 2] += w2 + d2 * dz
    zp[b, i + 3] += w3 + d3 * dz
    dzp[i], dzp[i + 1], dzp[i + 2], dzp[i + 3] = d0, d1, d2, d3
    val = 0.0
    for k in range(d):
        val += G[b, k] * zp[b, k]
    der = G[b, i] * d0 + G[b, i + 1] * d1 + G[b, i + 2] * d2 + G[b, i + 3] * d3
    return val, der


@_jit
def _branches(V, G, lo, hi, linear, signed, knots, B0, s, zp, dzp, g, dg):
    """Branch values ``g``, their derivatives ``dg`` with respect to the
    branch input, and ``zp[b, k]``, the derivative of ``g_b`` with respect to
    ``G[b, k]``, at ``z = V^T s`` (continued outside ``[lo, hi]``);
    polynomial branches (``knots`` None; in signed powers when ``signed``),
    or splines on ``knots`` (r, 2) with offsets ``B0`` (r, d). ``dzp`` (d,)
    is scratch."""
    r, d = G.shape
    for b in range(r):
        z = 0.0
        for j in range(s.shape[0]):
            z += V[j, b] * s[j]
        zc = min(max(z, lo[b]), hi[b])  # the point the branch is evaluated at
        if knots is not None:  # pruned when compiled for polynomials
            val, der = _spline_at(G, b, knots, B0, zc, zp, dzp)
        else:
            val, der = _polynomial_at(G, b, signed, zc, zp, dzp)
        if zc != z:
            if linear:
                # Tangent continuation: g(zc) + g'(zc) (z - zc).
                val += der * (z - zc)
                for k in range(d):
                    zp[b, k] += dzp[k] * (z - zc)
            else:
                der = 0.0  # held at the edge: no dependence on z
        g[b] = val
        dg[b] = der


@_jit
def _polynomial_value(G, b, signed, zc):
    """g_b(zc) alone, summed as :func:`_polynomial_at` sums it (the same
    bits) without its derivative and tables, which a simulation reads only
    where a branch input leaves its range."""
    val = 0.0
    sign = -1.0 if signed and zc < 0.0 else 1.0
    zk = 1.0
    for k in range(G.shape[1]):
        zk *= zc
        val += G[b, k] * (zk * (sign if k % 2 == 1 else 1.0))
    return val


@_jit
def _branch_values(V, G, lo, hi, linear, signed, knots, B0, s, zp, dzp, g):
    """Branch values ``g`` at ``z = V^T s``, as :func:`_branches` gives
    them; ``zp`` and ``dzp`` are scratch. A simulation needs no
    derivatives: those of a polynomial branch are computed only where
    its input is continued past its range (the simulation of a
    five-branch, degree-8 model of Bouc-Wen: 87 -> 61 ns a sample, the
    same bits)."""
    r = G.shape[0]
    for b in range(r):
        z = 0.0
        for j in range(s.shape[0]):
            z += V[j, b] * s[j]
        zc = min(max(z, lo[b]), hi[b])
        if knots is not None or (zc != z and linear):
            if knots is not None:  # pruned when compiled for polynomials
                val, der = _spline_at(G, b, knots, B0, zc, zp, dzp)
            else:
                val, der = _polynomial_at(G, b, signed, zc, zp, dzp)
            if zc != z and linear:
                val += der * (z - zc)
        else:
            val = _polynomial_value(G, b, signed, zc)
        g[b] = val


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
def _linearised(L, W, dg, V, out):
    """out = L + W diag(dg) Vx^T, the local linear map of x (Vx: the first
    ``L.shape[1]`` rows of V)."""
    for i in range(L.shape[0]):
        for k in range(L.shape[1]):
            acc = L[i, k]
            for b in range(W.shape[1]):
                acc += W[i, b] * dg[b] * V[k, b]
            out[i, k] = acc


@_jit
def _branch_direct(w, dg, s, zp, oV, oG, row):
    """Add the direct dependence of ``w . g(V^T s)`` on V and G to ``row``.
    Each entry of the row takes one term, so the order is free: V's entries
    (``oV + j r + b``) are taken in the order they lie in, b innermost,
    rather than with a stride of r (Bouc-Wen, three states and branches:
    the Jacobian 3.9 -> 3.1 ms a call, the same bits). Each run of entries
    is written through a view that starts at it, indexed by the loop's own
    variable: numba then knows the index is not negative and the loop is
    vectorised; indexed ``row[oG + b d + k]``, every entry went through
    numba's negative-index test and none was (the three state rows of a
    six-branch, degree-11 model: 188 -> 128 ns a sample)."""
    r, d = zp.shape
    for j in range(s.shape[0]):
        sj = s[j]
        run = row[oV + j * r : oV + (j + 1) * r]
        for b in range(r):
            c = w[b]
            if c != 0.0:
                run[b] += (c * dg[b]) * sj
    for b in range(r):
        c = w[b]
        if c == 0.0:
            continue
        run = row[oG + b * d : oG + (b + 1) * d]
        zb = zp[b]
        for k in range(d):
            run[k] += c * zb[k]


@_jit
def _copy_run(src, dst):
    """dst[:] = src, through views that start at the runs (see
    :func:`_branch_direct`)."""
    for q in range(src.shape[0]):
        dst[q] = src[q]


@_jit
def _add_run(src, dst):
    """dst += src, through views that start at the runs (see
    :func:`_branch_direct`)."""
    for q in range(src.shape[0]):
        dst[q] += src[q]


@_jit
def _combine_rows(c, S, lo, hi, out):
    """out = sum_k c[k] S[k, lo:hi], summed over k as a plain loop from zero
    sums it, ``0.0 + c[0] S[0, q] + c[1] S[1, q] + ...``, but three terms a
    pass over the row (then two a pass), not a pass per term that loads and
    stores the row again. The rows of S are taken as one-dimensional
    contiguous views: a view of the columns ``S[:, lo:hi]`` is not
    contiguous to numba, and its loops were not vectorised (an output row
    of 120 columns from three states, alone: 123 -> 27 ns)."""
    n, w = c.shape[0], hi - lo
    k = 0
    if n >= 3:
        c0, c1, c2 = c[0], c[1], c[2]
        s0, s1, s2 = S[0, lo:hi], S[1, lo:hi], S[2, lo:hi]
        for q in range(w):
            out[q] = ((0.0 + c0 * s0[q]) + c1 * s1[q]) + c2 * s2[q]
        k = 3
    else:
        for q in range(w):
            out[q] = 0.0
    while k + 2 <= n:
        c0, c1 = c[k], c[k + 1]
        s0, s1 = S[k, lo:hi], S[k + 1, lo:hi]
        for q in range(w):
            out[q] = (out[q] + c0 * s0[q]) + c1 * s1[q]
        k += 2
    if k < n:
        c0, s0 = c[k], S[k, lo:hi]
        for q in range(w):
            out[q] += c0 * s0[q]


# States up to which _carry_fused takes the sensitivities through the local
# linear map: 33 against 60 ns at 2 states, 45 against 94 at 3, as fast at 4
# (a decoupled model's columns, three branches of degree 7); BLAS above, 1.2
# to 1.9 times faster from 5 to 10 states (the same bits up to 10 here; from
# 18 on, BLAS blocks the sum over the states differently).
_FUSED_STATES = 4


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _carry_fused(M, S, out):
    """out = M S, each entry summed over k in order with every product
    fused into the sum (one rounding a term), ``fma(M[i, 2], S[2, q],
    fma(M[i, 1], S[1, q], 0.0 + M[i, 0] S[0, q]))``: the arithmetic of
    OpenBLAS's dgemm kernel at these sizes, so the same bits as the
    ``np.dot`` it replaces (checked from 2 to 10 states), without a library
    call per sample. Not inlined in the kernel: ``contract`` (fusing
    allowed) must stay on these sums alone. The first term is added to a
    zero so that the sum's first fusion is with it, and the order holds.
    The passes of :func:`_combine_rows`, written on the matrix: through it,
    row by row (the same bits), the Jacobian took 5 % longer."""
    n, w = M.shape[1], S.shape[1]
    for i in range(M.shape[0]):
        k = 0
        if n >= 3:
            c0, c1, c2 = M[i, 0], M[i, 1], M[i, 2]
            for q in range(w):
                out[i, q] = ((0.0 + c0 * S[0, q]) + c1 * S[1, q]) + c2 * S[2, q]
            k = 3
        else:
            c0 = M[i, 0]
            for q in range(w):
                out[i, q] = 0.0 + c0 * S[0, q]
            k = 1
        while k + 2 <= n:
            c0, c1 = M[i, k], M[i, k + 1]
            for q in range(w):
                out[i, q] = (out[i, q] + c0 * S[k, q]) + c1 * S[k + 1, q]
            k += 2
        if k < n:
            c0 = M[i, k]
            for q in range(w):
                out[i, q] = out[i, q] + c0 * S[k, q]


@numba.njit(cache=True, nogil=True)
def decoupled_simulate(A, B, C, D, Wx, Wy, V, G, lo, hi, linear, signed, knots, B0, U, x0):
    """Simulate; returns (Y, X, n_ok, x_end). n_ok < len(U) means the state
    left the range (divergence) after sample n_ok - 1."""
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    r, d = G.shape
    s = np.empty(n + m)
    zp = np.empty((r, d))
    dzp = np.empty(d)
    g = np.empty(r)
    dg = np.empty(r)
    Y = np.empty((N, p))
    X = np.empty((N, n))
    x = x0.copy()
    x_next = np.empty(n)
    for t in range(N):
        _stack(x, U[t], s)
        _branch_values(V, G, lo, hi, linear, signed, knots, B0, s, zp, dzp, g)
        X[t] = x
        _affine(C, x, D, U[t], Wy, g, Y[t])
        _affine(A, x, B, U[t], Wx, g, x_next)
        x, x_next = x_next, x
        for i in range(n):
            if not np.abs(x[i]) < DIVERGENCE_BOUND:  # also catches NaN
                return Y, X, t + 1, x
    return Y, X, N, x


@numba.njit(cache=True, nogil=True)
def decoupled_jacobian(A, B, C, D, Wx, Wy, V, G, lo, hi, linear, signed, knots, B0, U, x, Sx, n_skip,
                       out_branch_params, J):
    """Output sensitivities dy(t)/dtheta for t >= n_skip, written to
    J[(t - n_skip), :, :] (shape (N - n_skip, p, n_theta)). ``Wy`` is a
    parameter (the last block) only when ``out_branch_params``; otherwise it
    is held fixed, but still enters the output. Resumable: ``x`` and ``Sx``
    (n, n_sx), the state and its sensitivity at the first sample of ``U``,
    are advanced in place to the sample after the last. ``Sx`` may carry
    start-state columns after the n_sx parameters', as in
    ``pnlss_jacobian``."""
    N, m = U.shape
    n = A.shape[0]
    p = C.shape[0]
    r, d = G.shape
    oA = 0
    oB = oA + n * n
    oW = oB + n * m
    oV = oW + n * r
    oG = oV + (n + m) * r
    n_sx = oG + r * d  # parameters that move the state
    n_cols = Sx.shape[1]  # and the start-state columns after them
    n_par = J.shape[2] - (n_cols - n_sx)
    oC = n_sx
    oD = oC + p * n
    oWy = oD + p * m
    s = np.empty(n + m)
    zp = np.empty((r, d))
    dzp = np.empty(d)
    g = np.empty(r)
    dg = np.empty(r)
    S = Sx.copy()  # dx/dtheta for the state-moving parameters
    S_next = np.empty((n, n_cols))
    Ax = np.empty((n, n))  # A + Wx diag(g') Vx^T
    Cx = np.empty((p, n))  # C + Wy diag(g') Vx^T
    x_now = x.copy()
    x_next = np.empty(n)
    for t in range(N):
        u = U[t]
        _stack(x_now, u, s)
        _branches(V, G, lo, hi, linear, signed, knots, B0, s, zp, dzp, g, dg)
        _linearised(A, Wx, dg, V, Ax)
        if t >= n_skip:
            _linearised(C, Wy, dg, V, Cx)
            Jt = J[t - n_skip]
            for a in range(p):
                row = Jt[a]
                _combine_rows(Cx[a], S, 0, n_sx, row[:n_sx])
                for q in range(n_sx, n_par):
                    row[q] = 0.0
                _combine_rows(Cx[a], S, n_sx, n_cols, row[n_par:])  # the start-state columns
                _branch_direct(Wy[a], dg, s, zp, oV, oG, row)
                _copy_run(x_now, row[oC + a * n : oC + (a + 1) * n])
                _copy_run(u, row[oD + a * m : oD + (a + 1) * m])
                if out_branch_params:
                    _copy_run(g, row[oWy + a * r : oWy + (a + 1) * r])
        # Sensitivity of the next state: the propagated part, a product BLAS
        # does at three times the rate of a compiled loop at 18 states and
        # 450 columns (5.7 against 17 us a sample) but that costs more in its
        # call than in its sums at a few states, then the direct dependence of
        # row i on the parameters.
        if n <= _FUSED_STATES:
            _carry_fused(Ax, S, S_next)
        else:
            np.dot(Ax, S, S_next)
        for i in range(n):
            row = S_next[i]
            _add_run(x_now, row[oA + i * n : oA + (i + 1) * n])
            _add_run(u, row[oB + i * m : oB + (i + 1) * m])
            _add_run(g, row[oW + i * r : oW + (i + 1) * r])
            _branch_direct(Wx[i], dg, s, zp, oV, oG, row)
        S, S_next = S_next, S
        _affine(A, x_now, B, u, Wx, g, x_next)
        x_now, x_next = x_next, x_now
    x[:] = x_now
    Sx[:, :] = S
