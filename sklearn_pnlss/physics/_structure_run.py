"""Compiled Newmark integrator of a linear structure with nonlinear connections.

Equation: ``M ydd + C yd + K y + D F(D^T y, D^T yd, z) = P u``, where
column ``c`` of ``D`` maps the degrees of freedom to connection ``c``'s
relative displacement (a point's displacement less another's, or less the
ground's) and ``F`` are the force elements of :mod:`.forces`, one per
connection, acting on that relative motion; internal states follow
``zd = g(D^T y, D^T yd, z)``.  ``y`` uses Newmark average acceleration, ``z``
the trapezoidal rule, as the single oscillator of :mod:`._newmark` does.

Why a second kernel: the step's equations are linear in ``y`` but for the
connections, so ``y_{n+1} = y_lin - W F`` with ``y_lin`` the linear
structure's step and ``W = K_eff^{-1} D``; only the connections' relative
motions ``r = D^T y`` and the internal states are solved by Newton
(``r = D^T y_lin - G F(r)``, ``G = D^T W``): a handful of unknowns whatever
the number of degrees of freedom, where Newton on all of ``y`` would solve
an n x n system per iteration.  The linear step is four matrix-vector
products with matrices made once per step length.

Sensitivities: the converged step's equations differentiated (the Newton
matrix at the solution, factored once per step and solved for every
direction), as :mod:`._newmark` does for the oscillator; a direction moves
the start state or one element parameter.
"""
import numpy as np
from numba import njit

from ._newmark import _INLINE, _JIT, _dparams, _factor_inplace, _force, _rate, _solve_factored

#: A Newton step is taken back halfway at most this many times in a row
#: where it leaves a larger residual.
NEWTON_HALVINGS = 8


@njit(**_INLINE)
def _matvec_add(out, a, x, scale):
    """out += scale * a @ x (a small dense matrix)."""
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += a[i, j] * x[j]
        out[i] += scale * s


@njit(**_INLINE)
def _relative(d_mat, vec, out):
    """out = D^T vec: the connections' relative motions."""
    for c in range(d_mat.shape[1]):
        s = 0.0
        for j in range(d_mat.shape[0]):
            s += d_mat[j, c] * vec[j]
        out[c] = s


@njit(**_INLINE)
def _connection_forces(kinds, p_off, params, z_off, r, rd, z, forces, dfdr, dfdrd, dfdz):
    """Each connection's force at its relative motion ``(r, rd)`` and the
    states ``z``, with its derivatives (``dfdz`` at the states' indices)."""
    for e in range(kinds.shape[0]):
        # no custom elements: a Connection takes the built-in ones only
        f, fr, frd = _force(kinds[e], params, p_off[e], p_off[e + 1], r[e], rd[e], z, z_off[e], dfdz, None)
        forces[e] = f
        dfdr[e] = fr
        dfdrd[e] = frd


@njit(**_INLINE)
def _state_rates(kinds, p_off, params, z_off, r, rd, z, g, dgdy, dgdyd, dgdz):
    for e in range(kinds.shape[0]):
        a, b = z_off[e], z_off[e + 1]
        if b > a:
            _rate(kinds[e], params, p_off[e], r[e], rd[e], z, a, b, g, dgdy, dgdyd, dgdz)


@njit(**_JIT)
def _parameter_partials(kinds, p_off, params, z_off, r, rd, z, dfdp, dgdp):
    """Every element's force and rate derivatives by its parameters.

    Called, not inlined: once a step, and only with sensitivities, while its
    two inlined copies (every element kind's parameter derivatives) took
    the loop's first compilation from 26 to 48 s. A sensitivity run of a
    two-point structure: 61-66 ms against 61-63 ms."""
    for e in range(kinds.shape[0]):
        _dparams(kinds[e], params, p_off[e], p_off[e + 1], r[e], rd[e], z, z_off[e], z_off[e + 1], dfdp, dgdp)


@njit(**_INLINE)
def _newton_matrix(jac, g_mat, z_off, owner, dfdr, dfdrd, dfdz, dgdy, dgdyd, dgdz, c_vel, half_h):
    """The step's Newton matrix in ``(r, z)`` at the point whose partial
    derivatives are given."""
    n_c = g_mat.shape[0]
    nz = owner.shape[0]
    n_x = n_c + nz
    for a in range(n_x):
        for b in range(n_x):
            jac[a, b] = 0.0
    for c in range(n_c):
        for k in range(n_c):
            jac[c, k] = g_mat[c, k] * (dfdr[k] + dfdrd[k] * c_vel)
        jac[c, c] += 1.0
        for j in range(nz):
            jac[c, n_c + j] = g_mat[c, owner[j]] * dfdz[j]
    for j in range(nz):
        e = owner[j]
        jac[n_c + j, e] = -half_h * (dgdy[j] + dgdyd[j] * c_vel)
        for col in range(z_off[e], z_off[e + 1]):
            jac[n_c + j, n_c + col] = -half_h * dgdz[j, col]
        jac[n_c + j, n_c + j] += 1.0


@njit(**_INLINE)
def _record_sensors(out, i, s_rows, s_kind, y, yd, ydd, d):
    """``out[i, k, d]``: sensor ``k``'s reading of the motion (y, yd, ydd)."""
    for k in range(s_rows.shape[0]):
        s = 0.0
        for j in range(s_rows.shape[1]):
            v = y[j] if s_kind[k] == 0 else (yd[j] if s_kind[k] == 1 else ydd[j])
            s += s_rows[k, j] * v
        out[i, k, d] = s


@njit(**_JIT)
def structure_run(u, n_steps, h, a_u, a_y, a_yd, a_ydd, w, g_mat, d_mat, p_mat, c_mat, k_mat, m_inv,
                  kinds, p_off, params, z_off, state, init_accel, y_out, yd_out, ydd_out, z_out, rtol, max_iter,
                  tangents, param_of, s_rows, s_kind, sens_out):
    """Integrate ``n_steps`` steps of length ``h`` from ``state`` (updated in
    place), laid out as ``[y (n), yd (n), ydd (n), z (nz), zd (nz)]``.

    Step ``i`` goes from time ``i h`` to ``(i + 1) h`` with the input row
    ``u[(i + 1) % len(u)]``; sample ``i`` of the outputs is the state at
    ``i h`` (the first ``len(y_out)`` samples are stored).  ``a_*`` are the
    linear step's matrices (``y_lin = a_u u + a_y y + a_yd yd + a_ydd ydd``),
    ``w = K_eff^{-1} D``, ``g_mat = D^T w``; ``p_mat, c_mat, k_mat, m_inv``
    give the starting acceleration when ``init_accel``.

    Sensitivities (none when ``tangents`` has no rows): each row of
    ``tangents`` is the derivative of the state (same layout) along one
    direction, updated in place; ``param_of[d]`` is the element parameter
    (an index into ``params``) the direction moves, -1 for none (a
    direction of the start state).  ``sens_out[i, k, d]`` receives sensor
    ``k``'s derivative at sample ``i``: row ``s_rows[k]`` of the
    displacement (``s_kind[k]`` 0), velocity (1) or acceleration (2).

    Returns
    -------
    n_failed : int
        Steps where Newton did not reach ``rtol`` within ``max_iter``.
    """
    n, n_c, nz = d_mat.shape[0], kinds.shape[0], z_off[kinds.shape[0]]
    n_x = n_c + nz
    owner = np.zeros(nz, dtype=np.int64)  # the connection each state belongs to
    for e in range(n_c):
        for j in range(z_off[e], z_off[e + 1]):
            owner[j] = e
    return _run(u, n_steps, h, a_u, a_y, a_yd, a_ydd, w, g_mat, d_mat, p_mat, c_mat, k_mat, m_inv, kinds, p_off,
                params, z_off, state, init_accel, y_out, yd_out, ydd_out, z_out, rtol, max_iter, tangents, param_of,
                s_rows, s_kind, sens_out, owner, np.zeros((6, n)), np.zeros((12, n_c)), np.zeros((7, nz)),
                np.zeros((5, n_x)), np.zeros((n_x, n_x)), np.zeros((nz, nz)), np.zeros(params.shape[0]),
                np.zeros((nz, params.shape[0])), np.zeros(n_x, dtype=np.int64))


# Compiled without reference counting (``_nrt=False``): every work array
# of the loop is a view of one made by ``structure_run``, and the counts
# kept on them (the views, the arguments of the inlined helpers) took 63 %
# of a step of a 5-point chain with a cubic spring (measured with perf: the
# time in NRT_incref and NRT_decref).  Nothing here may allocate.
@njit(_nrt=False, **_JIT)
def _run(u, n_steps, h, a_u, a_y, a_yd, a_ydd, w, g_mat, d_mat, p_mat, c_mat, k_mat, m_inv, kinds, p_off, params,
         z_off, state, init_accel, y_out, yd_out, ydd_out, z_out, rtol, max_iter, tangents, param_of, s_rows, s_kind,
         sens_out, owner, n_work, c_work, z_work, x_work, jac, dgdz, dfdp, dgdp, pivots):
    """The time loop of :func:`structure_run` on work arrays it made:
    ``n_work`` (6, n), ``c_work`` (12, n_c), ``z_work`` (7, nz), ``x_work``
    (5, n_x), ``jac`` and ``dgdz`` square, ``dfdp`` and ``dgdp`` by the
    parameters, ``pivots``."""
    n = d_mat.shape[0]
    n_c = kinds.shape[0]
    nz = z_off[n_c]
    n_x = n_c + nz
    n_u = u.shape[0]
    n_out = y_out.shape[0]
    n_dir = tangents.shape[0]
    n_sens_out = sens_out.shape[0]
    c_acc = 4.0 / (h * h)
    c_vel = 2.0 / h
    half_h = 0.5 * h

    y, yd, ydd, y_lin, dy_lin, load = n_work[0], n_work[1], n_work[2], n_work[3], n_work[4], n_work[5]
    for j in range(n):
        y[j], yd[j], ydd[j] = state[j], state[n + j], state[2 * n + j]
    r, rd, r_prev, rd_prev, r_lin, forces = c_work[0], c_work[1], c_work[2], c_work[3], c_work[4], c_work[5]
    dfdr, dfdrd, d_rd_const, d_force, sr, srd = c_work[6], c_work[7], c_work[8], c_work[9], c_work[10], c_work[11]
    z, zd, dfdz, g, dgdy, dgdyd, zq = z_work[0], z_work[1], z_work[2], z_work[3], z_work[4], z_work[5], z_work[6]
    for j in range(nz):
        z[j], zd[j] = state[3 * n + j], state[3 * n + nz + j]
    res, peak, x, x0, scale_x = x_work[0], x_work[1], x_work[2], x_work[3], x_work[4]

    _relative(d_mat, y, r)
    _relative(d_mat, yd, rd)
    if init_accel:
        _connection_forces(kinds, p_off, params, z_off, r, rd, z, forces, dfdr, dfdrd, dfdz)
        load.fill(0.0)
        _matvec_add(load, p_mat, u[0], 1.0)
        _matvec_add(load, c_mat, yd, -1.0)
        _matvec_add(load, k_mat, y, -1.0)
        _matvec_add(load, d_mat, forces, -1.0)
        for i in range(n):
            ydd[i] = 0.0
        _matvec_add(ydd, m_inv, load, 1.0)
        _state_rates(kinds, p_off, params, z_off, r, rd, z, zd, dgdy, dgdyd, dgdz)
        if n_dir > 0:
            # the start's acceleration and rates move with its positions
            # and the parameters: the equation of motion differentiated
            _parameter_partials(kinds, p_off, params, z_off, r, rd, z, dfdp, dgdp)
            for d in range(n_dir):
                tan = tangents[d]
                pi = param_of[d]
                _relative(d_mat, tan[0:n], sr)
                _relative(d_mat, tan[n:2 * n], srd)
                for c in range(n_c):
                    df = dfdr[c] * sr[c] + dfdrd[c] * srd[c]
                    for j in range(z_off[c], z_off[c + 1]):
                        df += dfdz[j] * tan[3 * n + j]
                    if pi >= 0 and p_off[c] <= pi < p_off[c + 1]:
                        df += dfdp[pi]
                    d_force[c] = df
                load.fill(0.0)
                _matvec_add(load, c_mat, tan[n:2 * n], -1.0)
                _matvec_add(load, k_mat, tan[0:n], -1.0)
                _matvec_add(load, d_mat, d_force, -1.0)
                for i in range(n):
                    tan[2 * n + i] = 0.0
                _matvec_add(tan[2 * n:3 * n], m_inv, load, 1.0)
                for j in range(nz):
                    e = owner[j]
                    rate = dgdy[j] * sr[e] + dgdyd[j] * srd[e]
                    for col in range(z_off[e], z_off[e + 1]):
                        rate += dgdz[j, col] * tan[3 * n + col]
                    if pi >= 0:
                        rate += dgdp[j, pi]
                    tan[3 * n + nz + j] = rate
    for c in range(n_c):
        peak[c] = abs(r[c])
    for j in range(nz):
        peak[n_c + j] = abs(z[j])

    n_failed = 0
    for i in range(n_steps + 1):
        if i < n_out:
            for j in range(n):
                y_out[i, j] = y[j]
                yd_out[i, j] = yd[j]
                ydd_out[i, j] = ydd[j]
            for j in range(nz):
                z_out[i, j] = z[j]
        if i < n_sens_out:
            for d in range(n_dir):
                tan = tangents[d]
                _record_sensors(sens_out, i, s_rows, s_kind, tan[0:n], tan[n:2 * n], tan[2 * n:3 * n], d)
        if i == n_steps:
            break
        iu = (i + 1) % n_u
        for j in range(n):
            s = 0.0
            for k in range(u.shape[1]):
                s += a_u[j, k] * u[iu, k]
            for k in range(n):
                s += a_y[j, k] * y[k] + a_yd[j, k] * yd[k] + a_ydd[j, k] * ydd[k]
            y_lin[j] = s
        _relative(d_mat, y_lin, r_lin)
        _relative(d_mat, y, r_prev)
        _relative(d_mat, yd, rd_prev)
        # predictor: the linear structure's step for the connections, the
        # states' rates held
        for c in range(n_c):
            r[c] = r_lin[c]
        for j in range(nz):
            zq[j] = z[j] + half_h * zd[j]

        # damped Newton: a step that leaves a larger residual is taken back
        # halfway (a steep law, a friction smoothed over a small velocity,
        # sends the full step far past the root and back, step after step,
        # and a failed step's force is noise in a fit's differences)
        for a in range(n_x):
            scale_x[a] = max(peak[a], abs(r[a]) if a < n_c else abs(zq[a - n_c]), 1e-30)
        converged = False
        best, halvings = np.inf, 0
        for it in range(max_iter):
            for c in range(n_c):
                rd[c] = c_vel * (r[c] - r_prev[c]) - rd_prev[c]
            _connection_forces(kinds, p_off, params, z_off, r, rd, zq, forces, dfdr, dfdrd, dfdz)
            _state_rates(kinds, p_off, params, z_off, r, rd, zq, g, dgdy, dgdyd, dgdz)
            norm = 0.0
            for c in range(n_c):
                s = r[c] - r_lin[c]
                for k in range(n_c):
                    s += g_mat[c, k] * forces[k]
                res[c] = -s
                norm += (s / scale_x[c]) ** 2
            for j in range(nz):
                s = zq[j] - z[j] - half_h * (zd[j] + g[j])
                res[n_c + j] = -s
                norm += (s / scale_x[n_c + j]) ** 2
            if not norm < best and halvings < NEWTON_HALVINGS and np.isfinite(best):
                halvings += 1
                for a in range(n_x):
                    if a < n_c:
                        r[a] = 0.5 * (x0[a] + r[a])
                    else:
                        zq[a - n_c] = 0.5 * (x0[a] + zq[a - n_c])
                continue
            best, halvings = norm, 0
            _newton_matrix(jac, g_mat, z_off, owner, dfdr, dfdrd, dfdz, dgdy, dgdyd, dgdz, c_vel, half_h)
            _factor_inplace(jac, pivots, n_x)
            _solve_factored(jac, pivots, res, n_x)
            ok = True
            finite = True
            for a in range(n_x):
                if a < n_c:
                    x0[a] = r[a]
                    r[a] += res[a]
                    value = r[a]
                else:
                    x0[a] = zq[a - n_c]
                    zq[a - n_c] += res[a]
                    value = zq[a - n_c]
                if not np.isfinite(value):
                    finite = False
                if abs(res[a]) > rtol * max(abs(value), peak[a]):
                    ok = False
            if not finite:
                break
            if ok:
                converged = True
                break
        if not converged:
            n_failed += 1

        # the step's end: the connections' forces at the solution move the
        # linear structure's step
        for c in range(n_c):
            rd[c] = c_vel * (r[c] - r_prev[c]) - rd_prev[c]
        _connection_forces(kinds, p_off, params, z_off, r, rd, zq, forces, dfdr, dfdrd, dfdz)
        if n_dir > 0:
            _state_rates(kinds, p_off, params, z_off, r, rd, zq, g, dgdy, dgdyd, dgdz)
            _parameter_partials(kinds, p_off, params, z_off, r, rd, zq, dfdp, dgdp)
            _newton_matrix(jac, g_mat, z_off, owner, dfdr, dfdrd, dfdz, dgdy, dgdyd, dgdz, c_vel, half_h)
            _factor_inplace(jac, pivots, n_x)
            for d in range(n_dir):
                tan = tangents[d]
                pi = param_of[d]
                for j in range(n):
                    dy_lin[j] = 0.0
                _matvec_add(dy_lin, a_y, tan[0:n], 1.0)
                _matvec_add(dy_lin, a_yd, tan[n:2 * n], 1.0)
                _matvec_add(dy_lin, a_ydd, tan[2 * n:3 * n], 1.0)
                _relative(d_mat, dy_lin, sr)
                _relative(d_mat, tan[0:n], srd)  # the start's relative displacement
                _relative(d_mat, tan[n:2 * n], d_rd_const)
                for c in range(n_c):
                    # rd = c_vel r + (-c_vel r_prev - rd_prev): its constant part moves
                    d_rd_const[c] = -c_vel * srd[c] - d_rd_const[c]
                for c in range(n_c):
                    explicit = dfdrd[c] * d_rd_const[c]
                    if pi >= 0 and p_off[c] <= pi < p_off[c + 1]:
                        explicit += dfdp[pi]
                    d_force[c] = explicit
                for c in range(n_c):
                    s_c = sr[c]
                    for k in range(n_c):
                        s_c -= g_mat[c, k] * d_force[k]
                    x[c] = s_c
                for j in range(nz):
                    e = owner[j]
                    v = tan[3 * n + j] + half_h * (tan[3 * n + nz + j] + dgdyd[j] * d_rd_const[e])
                    if pi >= 0:
                        v += half_h * dgdp[j, pi]
                    x[n_c + j] = v
                _solve_factored(jac, pivots, x, n_x)
                # the forces' full change: through r, rd and the states
                for c in range(n_c):
                    df = d_force[c] + (dfdr[c] + dfdrd[c] * c_vel) * x[c]
                    for j in range(z_off[c], z_off[c + 1]):
                        df += dfdz[j] * x[n_c + j]
                    d_force[c] = df
                for j in range(n):
                    dy1 = dy_lin[j]
                    for c in range(n_c):
                        dy1 -= w[j, c] * d_force[c]
                    tan[2 * n + j] = c_acc * (dy1 - tan[j] - h * tan[n + j]) - tan[2 * n + j]
                    tan[n + j] = c_vel * (dy1 - tan[j]) - tan[n + j]
                    tan[j] = dy1
                for j in range(nz):
                    tan[3 * n + j] = x[n_c + j]
                # the rates at the step's end move with (r, rd, z) there
                for j in range(nz):
                    e = owner[j]
                    rate = dgdy[j] * x[e] + dgdyd[j] * (c_vel * x[e] + d_rd_const[e])
                    for col in range(z_off[e], z_off[e + 1]):
                        rate += dgdz[j, col] * x[n_c + col]
                    if pi >= 0:
                        rate += dgdp[j, pi]
                    tan[3 * n + nz + j] = rate
        for j in range(n):
            s = y_lin[j]
            for c in range(n_c):
                s -= w[j, c] * forces[c]
            ydd[j] = c_acc * (s - y[j] - h * yd[j]) - ydd[j]
            yd[j] = c_vel * (s - y[j]) - yd[j]
            y[j] = s
        for j in range(nz):
            z[j] = zq[j]
        _relative(d_mat, y, r)
        _relative(d_mat, yd, rd)
        _state_rates(kinds, p_off, params, z_off, r, rd, z, zd, dgdy, dgdyd, dgdz)
        for c in range(n_c):
            peak[c] = max(peak[c], abs(r[c]))
        for j in range(nz):
            peak[n_c + j] = max(peak[n_c + j], abs(z[j]))

    for j in range(n):
        state[j], state[n + j], state[2 * n + j] = y[j], yd[j], ydd[j]
    for j in range(nz):
        state[3 * n + j], state[3 * n + nz + j] = z[j], zd[j]
    return n_failed
