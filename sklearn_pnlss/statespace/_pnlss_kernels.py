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


@numba.njit(cache=True, nogil=True)
def _most_variables(exps):
    """The most variables one monomial holds (at least 1)."""
    c = 1
    for j in range(exps.shape[0]):
        held = 0
        for v in range(exps.shape[1]):
            if exps[j, v] > 0:
                held += 1
        c = max(c, held)
    return c


@numba.njit(cache=True, nogil=True)
def _value_factors(exps, width, at_least=1):
    """Where each monomial reads its factors, as flat indices into the
    powers table ``pw`` (``width`` columns), padded with index 0 (``pw[0, 0]
    = 1``): a monomial of degree d holds at most d variables, so it costs a
    few products, not one per variable. ``at_least``: columns, padded too
    (a product by one is exact)."""
    values = np.zeros((exps.shape[0], max(at_least, _most_variables(exps))), dtype=np.int64)
    for j in range(exps.shape[0]):
        a = 0
        for v in range(exps.shape[1]):
            if exps[j, v] > 0:
                values[j, a] = v * width + exps[j, v]
                a += 1
    return values


@numba.njit(cache=True, nogil=True)
def _derivative_factors(exps, n, width, at_least=1):
    """The state derivatives of the monomials that can be nonzero, one
    entry per (monomial j, state k): ``rows`` j, ``states`` k, ``coefs``
    (the exponent) and ``factors`` (flat indices into ``pw``, padded with
    index 0): d monomial_j / d x_k = coef * prod of pw at factors, the
    derivative's own power first, the others in increasing order (the
    products of dense loops, without their unit factors). F-16, ten states,
    degrees 2 and 3: 650 entries against 2,750 of the dense loops, which
    were 38 % of the Jacobian's recursion. ``at_least``: as for
    :func:`_value_factors`."""
    n_mon, n_vars = exps.shape
    n_d = 0
    for j in range(n_mon):
        for k in range(min(n, n_vars)):
            if exps[j, k] > 0:
                n_d += 1
    rows = np.empty(n_d, dtype=np.int64)
    states = np.empty(n_d, dtype=np.int64)
    coefs = np.empty(n_d)
    factors = np.zeros((n_d, max(at_least, _most_variables(exps))), dtype=np.int64)
    r = 0
    for j in range(n_mon):
        for k in range(min(n, n_vars)):
            e = exps[j, k]
            if e == 0:
                continue
            rows[r], states[r], coefs[r] = j, k, e
            factors[r, 0] = k * width + e - 1
            b = 1
            for v in range(n_vars):
                if v != k and exps[j, v] > 0:
                    factors[r, b] = v * width + exps[j, v]
                    b += 1
            r += 1
    return rows, states, coefs, factors


# A monomial's first factors and a derivative's first rows written out, in
# tables padded to at least as many: numba's loops of one to four iterations
# are vectorised for dozens, and the checks that send them to their scalar
# remainder cost more than their products (Bouc-Wen's Jacobian, three states,
# degrees 2 and 3: 3.6 -> 3.4 ms a call; its simulation 82 -> 77 ns a sample).
_FACTORS_OUT = 3
_ROWS_OUT = 4


@_jit
def _monomial_values(values, pwf, out):
    """The monomials from the flat powers table (see _value_factors,
    ``at_least=_FACTORS_OUT``), each ``1.0 * f0 * f1 * ...`` in that order."""
    for j in range(values.shape[0]):
        val = ((1.0 * pwf[values[j, 0]]) * pwf[values[j, 1]]) * pwf[values[j, 2]]
        for a in range(_FACTORS_OUT, values.shape[1]):
            val *= pwf[values[j, a]]
        out[j] = val


@_jit
def _padded_columns(W):
    """A copy of ``W`` with zero columns added up to ``_ROWS_OUT``."""
    out = np.zeros((W.shape[0], max(_ROWS_OUT, W.shape[1])))
    out[:, : W.shape[1]] = W
    return out


@_jit
def _linearised(L, Wt, derivatives, pwf, inside, work, out):
    """out = L + W dmon/dx: the local linear map of x (A + E dzeta/dx, or
    C + F deta/dx), each derivative of the monomials formed where it is
    used (see _derivative_factors); none through a state held at its edge.
    ``Wt`` is W transposed, its columns padded with zeros to at least
    ``_ROWS_OUT`` (:func:`_padded_columns`), and ``work`` (n, as many) a
    scratch array: the sum runs along W's columns, contiguous there.
    ``derivatives``: ``at_least=_FACTORS_OUT`` (see _monomial_values)."""
    rows, states, coefs, factors = derivatives
    n, n_out = L.shape[1], L.shape[0]
    work[:, :] = 0.0
    for r in range(rows.shape[0]):
        k = states[r]
        if not inside[k]:
            continue
        d = ((coefs[r] * pwf[factors[r, 0]]) * pwf[factors[r, 1]]) * pwf[factors[r, 2]]
        for b in range(_FACTORS_OUT, factors.shape[1]):
            d *= pwf[factors[r, b]]
        j = rows[r]
        work[k, 0] += Wt[j, 0] * d
        work[k, 1] += Wt[j, 1] * d
        work[k, 2] += Wt[j, 2] * d
        work[k, 3] += Wt[j, 3] * d
        for i in range(_ROWS_OUT, n_out):
            work[k, i] += Wt[j, i] * d
    for i in range(n_out):
        for k in range(n):
            out[i, k] = L[i, k] + work[k, i]


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
def _padded_rows(M, N, P):
    """``[M, N, P]`` as the rows of one array of zeros padded to a multiple
    of 4 rows (see :func:`_rows_times`)."""
    n_rows, a, b = M.shape[0], M.shape[1], M.shape[1] + N.shape[1]
    W = np.zeros((-(-n_rows // 4) * 4, b + P.shape[1]))
    W[:n_rows, :a], W[:n_rows, a:b], W[:n_rows, b:] = M, N, P
    return W


@_jit
def _rows_times(W, T, n_rows, out):
    """out[i] = W[i] . T for i < n_rows (``W`` from :func:`_padded_rows`),
    each row summed term by term in the order of ``_affine`` (its blocks
    concatenated in ``T``), four rows a pass: their chains of additions,
    each waiting on the one before, run side by side (the state update of
    a simulation: 101 -> 82 ns a sample on Bouc-Wen, the same bits)."""
    for i in range(0, n_rows, 4):
        a0 = a1 = a2 = a3 = 0.0
        for c in range(T.shape[0]):
            v = T[c]
            a0 += W[i, c] * v
            a1 += W[i + 1, c] * v
            a2 += W[i + 2, c] * v
            a3 += W[i + 3, c] * v
        out[i] = a0
        if i + 1 < n_rows:
            out[i + 1] = a1
        if i + 2 < n_rows:
            out[i + 2] = a2
        if i + 3 < n_rows:
            out[i + 3] = a3


@_jit
def _propagate(M, S, out):
    """out = M S, written out. Each entry is summed over k in a plain
    loop's order, ``0.0 + M[i, 0] S[0, q] + M[i, 1] S[1, q] + ...``, but
    three terms a pass over the row (then two a pass): a pass per term
    loaded and stored the row n times (Bouc-Wen's Jacobian, three states:
    4.1 -> 3.6 ms a call, the same bits)."""
    n, w = M.shape[1], S.shape[1]
    for i in range(M.shape[0]):
        k = 0
        if n >= 3:
            c0, c1, c2 = M[i, 0], M[i, 1], M[i, 2]
            for q in range(w):
                out[i, q] = ((0.0 + c0 * S[0, q]) + c1 * S[1, q]) + c2 * S[2, q]
            k = 3
        else:
            for q in range(w):
                out[i, q] = 0.0
        while k + 2 <= n:
            c0, c1 = M[i, k], M[i, k + 1]
            for q in range(w):
                out[i, q] = (out[i, q] + c0 * S[k, q]) + c1 * S[k + 1, q]
            k += 2
        if k < n:
            c0 = M[i, k]
            for q in range(w):
                out[i, q] += c0 * S[k, q]


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
    nv = n + m
    pw = np.empty((nv, _max_degree(exE, exF) + 1))
    pwf = pw.reshape(-1)
    s = np.empty(nv)
    inside = np.empty(nv, dtype=np.bool_)
    # the updates as rows [A, B, E] and [C, D, F] against the tables
    # [x; u; zeta] and [x; u; eta] (see _rows_times)
    WE, WF = _padded_rows(A, B, E), _padded_rows(C, D, F)
    TE, TF = np.empty(nv + exE.shape[0]), np.empty(nv + exF.shape[0])
    valE = _value_factors(exE, pw.shape[1], _FACTORS_OUT)
    valF = _value_factors(exF, pw.shape[1], _FACTORS_OUT)
    Y = np.empty((N, p))
    X = np.empty((N, n))
    x = x0.copy()
    for t in range(N):
        for i in range(n):
            TE[i] = TF[i] = x[i]
        for i in range(m):
            TE[n + i] = TF[n + i] = U[t, i]
        _stack(x, U[t], s)
        _hold(s, lo, hi, inside)
        _powers(s, pw)
        _monomial_values(valE, pwf, TE[nv:])
        _monomial_values(valF, pwf, TF[nv:])
        X[t] = x
        _rows_times(WF, TF, p, Y[t])
        _rows_times(WE, TE, n, x)
        for i in range(n):
            if not np.abs(x[i]) < DIVERGENCE_BOUND:  # also catches NaN
                return Y, X, t + 1, x
    return Y, X, N, x


@_jit
def _copy_run(src, dst):
    """dst[:] = src, through views that start at the runs: indexed from an
    offset (``J[t, a, c0 + q]``), each entry went through numba's
    negative-index test and the copy was not vectorised."""
    for q in range(src.shape[0]):
        dst[q] = src[q]


@_jit
def _add_run(src, dst):
    """dst += src, through views that start at the runs (see
    :func:`_copy_run`)."""
    for q in range(src.shape[0]):
        dst[q] += src[q]


@_jit
def _direct_columns(n, m, nE, c0, c1):
    """Where row i of the state's sensitivities takes its direct term from
    the term v of ``[x; u; zeta]``: the column, counted from ``c0``, of the
    parameter ``A[i, v]``, ``B[i, v - n]`` or ``E[i, v - n - m]``, or -1
    outside the columns ``c0:c1`` held. One loop over the terms with a
    table, where a loop per block (n, m and nE columns) indexed from the
    block's offset paid for three loops' entries (Bouc-Wen's Jacobian: 3.4
    -> 2.9 ms a call); used for a span that holds part of the columns (a
    span that holds them all takes the blocks as runs through views)."""
    nv = n + m
    out = np.full((n, nv + nE), -1, dtype=np.int64)
    for i in range(n):
        for v in range(nv + nE):
            if v < n:
                col = i * n + v
            elif v < nv:
                col = n * n + i * m + v - n
            else:
                col = n * nv + i * nE + v - nv
            if c0 <= col < c1:
                out[i, v] = col - c0
    return out


@numba.njit(cache=True, nogil=True)
def pnlss_jacobian(A, B, C, D, E, F, exE, exF, lo, hi, U, x, x_end, Sx, n_skip, J, c0, c1):
    """Output sensitivities dy(t)/dtheta for t >= n_skip, written to
    J[(t - n_skip), :, :] (shape (N - n_skip, p, n_theta)).

    Resumable, so that a long signal can be taken in blocks of samples
    (memory): ``x`` (n,) is the state and ``Sx`` (n, n_sx) its sensitivity
    to the parameters that move the state at the first sample of ``U``; the
    state after the last sample is written to ``x_end`` and ``Sx`` advanced
    in place. ``Sx`` may carry more columns than the n_sx parameters:
    sensitivities to a start state, propagated without direct terms and
    written to the last columns of ``J`` (after the parameters'; see
    ``StateSpaceModel.jacobian_blocks``).

    Only the columns ``c0:c1`` of ``Sx`` are carried (and their columns of
    ``J`` written; the one that starts at 0 writes the output parameters'
    too): each column's recursion depends on the state alone, so threads
    given disjoint ranges share the work, each simulating the state itself.

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
    w = c1 - c0
    oC = n_sx
    oD = oC + p * n
    oF = oD + p * m
    pw = np.empty((n + m, _max_degree(exE, exF) + 1))
    pwf = pw.reshape(-1)
    s = np.empty(n + m)
    inside = np.empty(n + m, dtype=np.bool_)
    T = np.empty(n + m + nE)  # [x; u; zeta]: the terms of the state update and its direct sensitivities
    zeta = T[n + m :]
    eta = np.empty(nF)
    valE = _value_factors(exE, pw.shape[1], _FACTORS_OUT)
    valF = _value_factors(exF, pw.shape[1], _FACTORS_OUT)
    derE = _derivative_factors(exE, n, pw.shape[1], _FACTORS_OUT)
    derF = _derivative_factors(exF, n, pw.shape[1], _FACTORS_OUT)
    # The state's and the output's local linear maps stacked, M = [Ax; Cx],
    # so one product M S carries the sensitivities to the next state and to
    # the output (S read once per sample). Two work arrays, swapped every
    # sample: S is the first n rows of one, the product goes to the other.
    M = np.empty((n + p, n))
    Ax, Cx = M[:n], M[n:]  # A + E dzeta/dx, C + F deta/dx
    P = np.empty((n + p, w))
    P_next = np.empty((n + p, w))
    P[:n] = Sx[:, c0:c1]
    Et, Ft = _padded_columns(E.T), _padded_columns(F.T)  # see _linearised
    work = np.empty((n, max(Et.shape[1], Ft.shape[1])))
    n_own = max(0, min(w, n_sx - c0))  # the span's columns of parameters, then of the start state
    direct = _direct_columns(n, m, nE, c0, c1)
    whole, nv = c0 == 0 and c1 >= n_sx, n + m  # the span holds every parameter that moves the state
    x_now = x.copy()
    x_next = np.empty(n)
    for t in range(N):
        u = U[t]
        _stack(x_now, u, s)
        _hold(s, lo, hi, inside)
        _powers(s, pw)
        _monomial_values(valE, pwf, zeta)
        for i in range(n):
            T[i] = x_now[i]
        for i in range(m):
            T[n + i] = u[i]
        _linearised(A, Et, derE, pwf, inside, work, Ax)
        S = P[:n]
        if t >= n_skip:
            _monomial_values(valF, pwf, eta)
            _linearised(C, Ft, derF, pwf, inside, work, Cx)
            _carry(M, S, P_next)
            Jt = J[t - n_skip]
            for a in range(p):
                Jx, Ja = P_next[n + a], Jt[a]
                _copy_run(Jx[:n_own], Ja[c0 : c0 + n_own])
                _copy_run(Jx[n_own:w], Ja[n_par + c0 + n_own - n_sx : n_par + c0 + w - n_sx])
                if c0 == 0:
                    Ja[n_sx:n_par] = 0.0
                    _copy_run(x_now, Ja[oC + a * n : oC + (a + 1) * n])
                    _copy_run(u, Ja[oD + a * m : oD + (a + 1) * m])
                    _copy_run(eta, Ja[oF + a * nF : oF + (a + 1) * nF])
        else:
            _carry(Ax, S, P_next[:n])
        # Sensitivity of the next state: the propagated part, then the
        # direct dependence of row i on its own parameters: when the span
        # holds them all, three runs of the row through views, which numba
        # vectorises (Bouc-Wen, degrees (2, 3) in the states and input: the
        # Jacobian 0.92 of the call through the table), else the table.
        if whole:
            for i in range(n):
                row = P_next[i]
                _add_run(T[:n], row[i * n : (i + 1) * n])
                _add_run(T[n:nv], row[n * n + i * m : n * n + (i + 1) * m])
                _add_run(zeta, row[n * nv + i * nE : n * nv + (i + 1) * nE])
        else:
            for i in range(n):
                for v in range(T.shape[0]):
                    c = direct[i, v]
                    if c >= 0:
                        P_next[i, c] += T[v]
        P, P_next = P_next, P
        _affine(A, x_now, B, u, E, zeta, x_next)
        x_now, x_next = x_next, x_now
    x_end[:] = x_now
    Sx[:, c0:c1] = P[:n]


@numba.njit(cache=True, nogil=True)
def pnlss_excursions_in_turn(A, B, E, exE, lo, hi, U, n_records, r0, r1, factor, stop_at_first, out):
    """The range excursion of each input ``U[i]`` (out[i]; see
    ``StateSpaceModel.runaways_in_turn``), the inputs dealt to
    ``n_records`` records (input i to record i % n_records), each record
    simulated in turn from rest, and from rest again after an input whose
    excursion exceeds ``factor`` (inf: the state diverged). Only records
    ``r0`` to ``r1 - 1`` are simulated here; with ``stop_at_first`` they
    stop at the first such input (out stays NaN after it).

    The records are simulated side by side, one sample of all of them at a
    time, with the record the innermost index of every array: the
    arithmetic of each sample is that of ``pnlss_simulate`` (the same
    results) in loops the compiler vectorises over the records. A loop so
    short (8 records) costs more to enter than its arithmetic, so each does
    as much as it can: a variable is held and raised to its first power in
    one, a monomial takes its (at most three) factors in one, and the state
    update sums four terms a loop, from one row of coefficients ``[A_i,
    B_i, E_i]`` against the rows ``[x; u; zeta]`` of one table, term by
    term in the order of ``pnlss_simulate``. Measured on Bouc-Wen (three
    states, 8 records): 33 ns a sample and record, against 56 ns with a
    loop per term and 100 ns one record at a time."""
    R, N, m = U.shape
    n = A.shape[0]
    nv = n + m
    n_mon = exE.shape[0]
    k = r1 - r0
    width = _max_degree(exE, exE[:0]) + 1
    values = _value_factors(exE, width)  # padded with pw[0] = 1: an exact product
    n_factors = values.shape[1]
    n_terms = nv + n_mon
    W = np.empty((n, n_terms))
    W[:, :n], W[:, n:nv], W[:, nv:] = A, B, E
    T = np.zeros((n_terms, k))  # [x; u; zeta], x carried from input to input of a record
    T_next = np.zeros((n_terms, k))
    pw = np.empty((nv * width, k))
    v_min = np.empty((nv, k))
    v_max = np.empty((nv, k))
    diverged = np.zeros(k, dtype=np.bool_)
    out[:] = np.nan
    for first in range(0, R, n_records):
        live = min(k, R - first - r0)  # records with an input at this turn
        if live <= 0:
            break
        v_min[:, :] = np.inf
        v_max[:, :] = -np.inf
        diverged[:] = False
        for t in range(N):
            for i in range(m):
                for b in range(live):
                    T[n + i, b] = U[first + r0 + b, t, i]
            for v in range(nv):
                lv, hv, base = lo[v], hi[v], v * width
                for b in range(live):
                    a = T[v, b]
                    v_min[v, b] = min(v_min[v, b], a)
                    v_max[v, b] = max(v_max[v, b], a)
                    pw[base, b] = 1.0
                    pw[base + 1, b] = 1.0 * min(max(a, lv), hv)
                for e in range(2, width):
                    for b in range(live):
                        pw[base + e, b] = pw[base + e - 1, b] * pw[base + 1, b]
            for j in range(n_mon):
                f0 = values[j, 0]
                if n_factors == 1:
                    for b in range(live):
                        T[nv + j, b] = pw[f0, b]
                elif n_factors == 2:
                    f1 = values[j, 1]
                    for b in range(live):
                        T[nv + j, b] = pw[f0, b] * pw[f1, b]
                else:
                    f1, f2 = values[j, 1], values[j, 2]
                    for b in range(live):
                        T[nv + j, b] = pw[f0, b] * pw[f1, b] * pw[f2, b]
                    for a in range(3, n_factors):
                        f = values[j, a]
                        for b in range(live):
                            T[nv + j, b] *= pw[f, b]
            for i in range(n):
                for b in range(live):
                    T_next[i, b] = 0.0
                c = 0
                while c + 4 <= n_terms:
                    w0, w1, w2, w3 = W[i, c], W[i, c + 1], W[i, c + 2], W[i, c + 3]
                    for b in range(live):
                        T_next[i, b] = (((T_next[i, b] + w0 * T[c, b]) + w1 * T[c + 1, b]) + w2 * T[c + 2, b]
                                        + w3 * T[c + 3, b])
                    c += 4
                for c in range(c, n_terms):
                    w = W[i, c]
                    for b in range(live):
                        T_next[i, b] += w * T[c, b]
            T, T_next = T_next, T
            for b in range(live):
                for i in range(n):
                    if not np.abs(T[i, b]) < DIVERGENCE_BOUND:  # also catches NaN
                        diverged[b] = True
                if diverged[b]:
                    T[:n, b] = 0.0  # the rest of this input is not looked at
        stop = False
        for b in range(live):
            excess = 0.0
            for v in range(nv):
                if hi[v] - lo[v] < np.inf:
                    excess = max(excess, max(lo[v] - v_min[v, b], v_max[v, b] - hi[v]) / (hi[v] - lo[v]))
            out[first + r0 + b] = np.inf if diverged[b] else excess
            if out[first + r0 + b] > factor:
                T[:n, b] = 0.0
                stop = stop or stop_at_first
        if stop:
            break
