"""Compiled Newmark / trapezoidal integrator of the oscillator with force elements.

Equation: ``m ydd + c yd + k y + sum_e F_e(y, yd, z_e) = u`` with internal
states ``zd_e = g_e(y, yd, z_e)``.  ``y`` uses Newmark average acceleration
(a = 1/2, b = 1/4), ``z`` the trapezoidal rule, and every step is solved by
Newton-Raphson on ``q = [y_{n+1}, z_{n+1}]`` with the exact Jacobian, because
the benchmark data were produced that way and only a fully converged solve
reproduces them to round-off.

Adding a force element type: write ``_xxx_force`` and (if it has internal
states) ``_xxx_rate`` below, add one branch to ``_force`` and ``_rate`` and a
class with the same kind code in :mod:`.forces`.  Users' own stateless
elements arrive as one compiled function ``custom(slot, p, y, yd)`` (see
:func:`custom_dispatcher`), an argument of every kernel.

That argument is a numba ``cfunc`` of the fixed signature ``CUSTOM_SIGNATURE``:
its type is the same first-class function type in every process, so the
kernels compiled for it stay in numba's disk cache and a user's element costs
only the compilation of its own function.  A ``numba.njit`` function passed
instead would be typed by its identity, new in every process: every process
recompiled the whole integrator around it, and once such a type was in
the cache index saving any new entry failed ("underlying object has
vanished").
"""
import numpy as np
from numba import cfunc, njit, types
from numba.extending import overload

from .forces import (
    KIND_BOUC_WEN,
    KIND_COULOMB_FRICTION,
    KIND_COUPLED_MASS,
    KIND_CUBIC_STIFFNESS,
    KIND_CUSTOM,
    KIND_DEAD_ZONE_SPRING,
    KIND_QUADRATIC_DAMPING,
    KIND_QUADRATIC_STIFFNESS,
    KIND_SERIES_DAMPER,
    KIND_STIFFNESS_DRIFT,
)

_JIT = dict(cache=True, nogil=True)
# The element kernels and the small solves are inlined into the time loop:
# called as functions, every call passed its arrays with a reference count
# each (an element with internal states ran 22 % slower; results identical).
_INLINE = dict(_JIT, inline="always")
# The time loops are compiled without reference counting (numba's
# ``_nrt=False``): their caller makes every array they use (nothing in a
# loop may allocate).  The counts numba kept on the arrays passed to the
# inlined helpers took about a third of a step (measured with perf in
# NRT_incref and NRT_decref).
_LOOP = dict(_JIT, _nrt=False)

# Layout of the carried state vector: [y, yd, ydd, z_0..z_{nz-1}, zd_0..zd_{nz-1}].
STATE_Y, STATE_YD, STATE_YDD, STATE_Z = 0, 1, 2, 3


# --------------------------------------------------------------------------
# Element kernels.  ``_xxx_force`` returns (F, dF/dy, dF/dyd) and fills
# dF/dz; ``_xxx_rate`` fills g, dg/dy, dg/dyd and the square block dg/dz.
# They read their parameters from ``p[o:]`` and their states from ``z[a:]``
# and write at ``[a:]`` (``[a:, a:]`` for dg/dz) of the shared arrays: a
# slice per element and call would cost a reference count each, which made
# an element with internal states three times slower than one without.
# --------------------------------------------------------------------------
@njit(**_INLINE)
def _bouc_wen_force(p, o, y, yd, z, a, dfdz):
    dfdz[a] = 1.0
    return z[a], 0.0, 0.0


@njit(**_INLINE)
def _bouc_wen_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz):
    alpha, beta, gamma, delta, nu = p[o], p[o + 1], p[o + 2], p[o + 3], p[o + 4]
    zz = z[a]
    az = abs(zz)
    sz = np.sign(zz)
    if nu == 1.0:
        # Exact shortcut: avoids pow() in the hot loop for the benchmark case.
        pow_nu = az
        pow_nu1 = 1.0
    else:
        pow_nu1 = az ** (nu - 1.0)
        pow_nu = pow_nu1 * az
    ayd = abs(yd)
    g[a] = alpha * yd - beta * (gamma * ayd * pow_nu1 * zz + delta * yd * pow_nu)
    dgdy[a] = 0.0
    dgdyd[a] = alpha - beta * (gamma * np.sign(yd) * pow_nu1 * zz + delta * pow_nu)
    # d(|z|^(nu-1) z)/dz = nu |z|^(nu-1);  d|z|^nu/dz = nu |z|^(nu-1) sign(z)
    dgdz[a, a] = -beta * nu * pow_nu1 * (gamma * ayd + delta * yd * sz)


@njit(**_INLINE)
def _cubic_force(p, o, y, yd, z, a, dfdz):
    return p[o] * y * y * y, 3.0 * p[o] * y * y, 0.0


@njit(**_INLINE)
def _quadratic_force(p, o, y, yd, z, a, dfdz):
    return p[o] * y * y, 2.0 * p[o] * y, 0.0


@njit(**_INLINE)
def _coulomb_force(p, o, y, yd, z, a, dfdz):
    t = np.tanh(yd / p[o + 1])
    return p[o] * t, 0.0, p[o] * (1.0 - t * t) / p[o + 1]


@njit(**_INLINE)
def _quadratic_damping_force(p, o, y, yd, z, a, dfdz):
    return p[o] * yd * abs(yd), 0.0, 2.0 * p[o] * abs(yd)


@njit(**_INLINE)
def _softplus(x, s):
    """s log(1 + exp(x / s)) and its derivative, without overflow."""
    r = x / s
    if r > 0:
        e = np.exp(-r)
        return x + s * np.log1p(e), 1.0 / (1.0 + e)
    e = np.exp(r)
    return s * np.log1p(e), e / (1.0 + e)


@njit(**_INLINE)
def _dead_zone_force(p, o, y, yd, z, a, dfdz):
    kb, gap, s = p[o], p[o + 1], p[o + 2]
    up, dup = _softplus(y - gap, s)
    down, ddown = _softplus(-y - gap, s)
    return kb * (up - down), kb * (dup + ddown), 0.0


@njit(**_INLINE)
def _coupled_mass_force(p, o, y, yd, z, a, dfdz):
    c2, k2 = p[o + 1], p[o + 2]
    dfdz[a] = -k2
    dfdz[a + 1] = -c2
    return k2 * (y - z[a]) + c2 * (yd - z[a + 1]), k2, c2


@njit(**_INLINE)
def _coupled_mass_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz):
    m2, c2, k2 = p[o], p[o + 1], p[o + 2]
    g[a] = z[a + 1]
    g[a + 1] = (k2 * (y - z[a]) + c2 * (yd - z[a + 1])) / m2
    dgdy[a] = 0.0
    dgdy[a + 1] = k2 / m2
    dgdyd[a] = 0.0
    dgdyd[a + 1] = c2 / m2
    dgdz[a, a] = 0.0
    dgdz[a, a + 1] = 1.0
    dgdz[a + 1, a] = -k2 / m2
    dgdz[a + 1, a + 1] = -c2 / m2


@njit(**_INLINE)
def _series_damper_force(p, o, y, yd, z, a, dfdz):
    ks = p[o + 1]
    dfdz[a] = -ks
    return ks * (y - z[a]), ks, 0.0


@njit(**_INLINE)
def _series_damper_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz):
    # the massless node: the spring's force drives the damper
    relax = p[o + 1] / p[o]
    g[a] = relax * (y - z[a])
    dgdy[a] = relax
    dgdyd[a] = 0.0
    dgdz[a, a] = -relax


@njit(**_INLINE)
def _drift_force(p, o, y, yd, z, a, dfdz):
    # z[a] is the clock: the stiffness is k + rate * t.
    dfdz[a] = p[o] * y
    return p[o] * z[a] * y, p[o] * z[a], 0.0


@njit(**_INLINE)
def _clock_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz):
    g[a] = 1.0
    dgdy[a] = 0.0
    dgdyd[a] = 0.0
    dgdz[a, a] = 0.0


@njit(**_INLINE)
def _force(kind, p, o, end, y, yd, z, a, dfdz, custom):
    """Force of the element of ``kind`` whose parameters are ``p[o:end]``
    and whose states start at ``z[a]``."""
    if kind == KIND_BOUC_WEN:
        return _bouc_wen_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_CUBIC_STIFFNESS:
        return _cubic_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_QUADRATIC_STIFFNESS:
        return _quadratic_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_COULOMB_FRICTION:
        return _coulomb_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_QUADRATIC_DAMPING:
        return _quadratic_damping_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_DEAD_ZONE_SPRING:
        return _dead_zone_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_COUPLED_MASS:
        return _coupled_mass_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_STIFFNESS_DRIFT:
        return _drift_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_SERIES_DAMPER:
        return _series_damper_force(p, o, y, yd, z, a, dfdz)
    elif kind == KIND_CUSTOM:
        # a user's function sees its own parameters only
        return _call_custom(custom, int(p[o]), p[o + 1:end], y, yd)
    return np.nan, np.nan, np.nan  # unknown kind: poison the result, never hang


@njit(**_INLINE)
def _rate(kind, p, o, y, yd, z, a, b, g, dgdy, dgdyd, dgdz):
    """Rates of the element's states ``z[a:b]``."""
    if kind == KIND_BOUC_WEN:
        _bouc_wen_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz)
    elif kind == KIND_COUPLED_MASS:
        _coupled_mass_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz)
    elif kind == KIND_STIFFNESS_DRIFT:
        _clock_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz)
    elif kind == KIND_SERIES_DAMPER:
        _series_damper_rate(p, o, y, yd, z, a, g, dgdy, dgdyd, dgdz)
    else:
        for j in range(a, b):
            g[j] = np.nan


# --------------------------------------------------------------------------
# Parameter derivatives (the sensitivity recursion of ``newmark_run``):
# ``_dparams`` fills dF/dp at ``dfdp[o:end]`` and dg/dp at ``dgdp[a:b, o:end]``
# for the element's parameters ``p[o:end]``; an element without them
# (a user's function) writes NaN, and its oscillator is differenced instead.
# --------------------------------------------------------------------------
@njit(**_INLINE)
def _dparams(kind, p, o, end, y, yd, z, a, b, dfdp, dgdp):
    for i in range(o, end):
        dfdp[i] = 0.0
        for j in range(a, b):
            dgdp[j, i] = 0.0
    if kind == KIND_BOUC_WEN:
        alpha, beta, gamma, delta, nu = p[o], p[o + 1], p[o + 2], p[o + 3], p[o + 4]
        zz = z[a]
        az = abs(zz)
        pow_nu1 = 1.0 if nu == 1.0 else az ** (nu - 1.0)
        pow_nu = pow_nu1 * az
        ayd = abs(yd)
        log_z = np.log(az) if az > 0.0 else 0.0
        dgdp[a, o] = yd
        dgdp[a, o + 1] = -(gamma * ayd * pow_nu1 * zz + delta * yd * pow_nu)
        dgdp[a, o + 2] = -beta * ayd * pow_nu1 * zz
        dgdp[a, o + 3] = -beta * yd * pow_nu
        dgdp[a, o + 4] = -beta * (gamma * ayd * pow_nu1 * zz + delta * yd * pow_nu) * log_z
    elif kind == KIND_CUBIC_STIFFNESS:
        dfdp[o] = y * y * y
    elif kind == KIND_QUADRATIC_STIFFNESS:
        dfdp[o] = y * y
    elif kind == KIND_COULOMB_FRICTION:
        t = np.tanh(yd / p[o + 1])
        dfdp[o] = t
        dfdp[o + 1] = -p[o] * (1.0 - t * t) * yd / (p[o + 1] * p[o + 1])
    elif kind == KIND_QUADRATIC_DAMPING:
        dfdp[o] = yd * abs(yd)
    elif kind == KIND_DEAD_ZONE_SPRING:
        kb, gap, s = p[o], p[o + 1], p[o + 2]
        up, dup = _softplus(y - gap, s)
        down, ddown = _softplus(-y - gap, s)
        dfdp[o] = up - down
        dfdp[o + 1] = kb * (ddown - dup)
        # d/ds of s log(1 + exp(x / s)): (softplus - x sigmoid) / s
        dfdp[o + 2] = kb * ((up - (y - gap) * dup) - (down - (-y - gap) * ddown)) / s
    elif kind == KIND_COUPLED_MASS:
        m2, c2, k2 = p[o], p[o + 1], p[o + 2]
        stretch, rate = y - z[a], yd - z[a + 1]
        dfdp[o + 1] = rate
        dfdp[o + 2] = stretch
        dgdp[a + 1, o] = -(k2 * stretch + c2 * rate) / (m2 * m2)
        dgdp[a + 1, o + 1] = rate / m2
        dgdp[a + 1, o + 2] = stretch / m2
    elif kind == KIND_STIFFNESS_DRIFT:
        dfdp[o] = z[a] * y
    elif kind == KIND_SERIES_DAMPER:
        cs, ks = p[o], p[o + 1]
        stretch = y - z[a]
        dfdp[o + 1] = stretch
        dgdp[a, o] = -ks * stretch / (cs * cs)
        dgdp[a, o + 1] = stretch / cs
    else:
        for i in range(o, end):
            dfdp[i] = np.nan


# ``custom(slot, p, y, yd) -> (F, dF/dy, dF/dyd)``: the kernels' custom
# element, ``slot`` the element's place among an oscillator's custom ones.
CUSTOM_SIGNATURE = types.UniTuple(types.float64, 3)(types.int64, types.float64[::1], types.float64,
                                                    types.float64)
# The compiled dispatchers, by the ids of their functions (kept alive with
# them, so the ids are never reused).
_DISPATCHERS = {}


@njit(nogil=True)
def _no_custom(slot, p, y, yd):
    """No custom element: a kernel of an oscillator without them, or the
    dispatch's end (a slot past the last custom element)."""
    return np.nan, np.nan, np.nan


def _call_custom(custom, slot, p, y, yd):
    """``custom(slot, p, y, yd)``, or NaNs when ``custom`` is None."""


@overload(_call_custom)
def _call_custom_typed(custom, slot, p, y, yd):
    # Chosen by the argument's type when a kernel is compiled: the kernels of
    # an oscillator without custom elements (``custom`` None) hold no call
    # to an unknown function, which cost their loops 3-9 % (the compiler
    # had to assume the call could write to any array).
    if isinstance(custom, types.NoneType):
        return lambda custom, slot, p, y, yd: _no_custom(slot, p, y, yd)
    return lambda custom, slot, p, y, yd: custom(slot, p, y, yd)


def _chain(functions):
    """One ``njit`` function ``custom(slot, p, y, yd)`` calling
    ``functions[slot](p, y, yd)``."""
    if not functions:
        return _no_custom
    head, rest = functions[0], _chain(functions[1:])

    @njit(nogil=True)
    def dispatch(slot, p, y, yd):
        if slot == 0:
            return head(p, y, yd)
        return rest(slot - 1, p, y, yd)

    return dispatch


def custom_dispatcher(functions=()):
    """What every kernel takes as its last argument: None without custom
    elements, else a ``cfunc`` calling the custom elements' ``functions``
    (compiled ``f(p, y, yd)``) by slot, compiled once per tuple of functions
    and process (only the functions and this dispatch: the kernels come
    from the disk cache)."""
    functions = tuple(functions)
    if not functions:
        return None
    key = tuple(id(f) for f in functions)
    if key not in _DISPATCHERS:
        _DISPATCHERS[key] = (cfunc(CUSTOM_SIGNATURE, nogil=True)(_chain(functions)), functions)
    return _DISPATCHERS[key][0]


# --------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------
@njit(**_INLINE)
def _factor_inplace(a, pivots, n):
    """Gaussian elimination with partial pivoting of ``a`` (n x n), done
    once: ``a`` becomes its upper triangle with the multipliers below it,
    ``pivots[col]`` the row swapped into ``col``.  ``_solve_factored`` then
    repeats on a right-hand side exactly the operations a joint elimination
    of matrix and right-hand side would (the same numbers to the bit),
    without eliminating the matrix again: the sensitivities solve one
    matrix for many directions per step."""
    for col in range(n):
        piv = col
        best = abs(a[col, col])
        for r in range(col + 1, n):
            v = abs(a[r, col])
            if v > best:
                best = v
                piv = r
        pivots[col] = piv
        if piv != col:
            # the columns left of ``col`` hold the multipliers of the rows
            # where they stood at their step, as the right-hand side's
            # replay reads them: they stay
            for j in range(col, n):
                tmp = a[col, j]
                a[col, j] = a[piv, j]
                a[piv, j] = tmp
        d = a[col, col]
        for r in range(col + 1, n):
            f = a[r, col] / d
            if f != 0.0:
                for j in range(col + 1, n):
                    a[r, j] -= f * a[col, j]
            a[r, col] = f


@njit(**_INLINE)
def _solve_factored(a, pivots, b, n):
    """Solve with a matrix factored by ``_factor_inplace``; the solution
    overwrites b."""
    for col in range(n):
        piv = pivots[col]
        if piv != col:
            tmp = b[col]
            b[col] = b[piv]
            b[piv] = tmp
        for r in range(col + 1, n):
            f = a[r, col]
            if f != 0.0:
                b[r] -= f * b[col]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for j in range(r + 1, n):
            s -= a[r, j] * b[j]
        b[r] = s / a[r, r]


@njit(**_INLINE)
def _solve3(a00, a01, a02, a10, a11, a12, a20, a21, a22, b0, b1, b2):
    """``_factor_inplace`` and ``_solve_factored`` for n = 3 on scalars, the
    same operations in the same order; returns the solution."""
    if abs(a10) > abs(a00) and abs(a10) >= abs(a20):
        a00, a01, a02, b0, a10, a11, a12, b1 = a10, a11, a12, b1, a00, a01, a02, b0
    elif abs(a20) > abs(a00) and abs(a20) > abs(a10):
        a00, a01, a02, b0, a20, a21, a22, b2 = a20, a21, a22, b2, a00, a01, a02, b0
    f = a10 / a00
    if f != 0.0:
        a11 -= f * a01
        a12 -= f * a02
        b1 -= f * b0
    f = a20 / a00
    if f != 0.0:
        a21 -= f * a01
        a22 -= f * a02
        b2 -= f * b0
    if abs(a21) > abs(a11):
        a11, a12, b1, a21, a22, b2 = a21, a22, b2, a11, a12, b1
    f = a21 / a11
    if f != 0.0:
        a22 -= f * a12
        b2 -= f * b1
    x2 = b2 / a22
    x1 = (b1 - a12 * x2) / a11
    x0 = ((b0 - a01 * x1) - a02 * x2) / a00
    return x0, x1, x2


@njit(**_INLINE)
def _solve2_inplace(a, b):
    """``_factor_inplace`` and ``_solve_factored`` for n = 2 (one internal
    state), the same operations in the same order, unrolled."""
    if abs(a[1, 0]) > abs(a[0, 0]):
        a00, a01, b0, a10, a11, b1 = a[1, 0], a[1, 1], b[1], a[0, 0], a[0, 1], b[0]
    else:
        a00, a01, b0, a10, a11, b1 = a[0, 0], a[0, 1], b[0], a[1, 0], a[1, 1], b[1]
    f = a10 / a00
    if f != 0.0:
        a11 -= f * a01
        b1 -= f * b0
    b[1] = b1 / a11
    b[0] = (b0 - a01 * b[1]) / a00


@njit(**_INLINE)
def _total_force_and_rates(kinds, p_off, params, z_off, y, yd, z, zd, dfdz, dgdy, dgdyd, dgdz, custom):
    """Sum of element forces at (y, yd, z); fills the state rates zd."""
    total = 0.0
    for e in range(kinds.shape[0]):
        a, b = z_off[e], z_off[e + 1]
        f, _, _ = _force(kinds[e], params, p_off[e], p_off[e + 1], y, yd, z, a, dfdz, custom)
        total += f
        if b > a:
            _rate(kinds[e], params, p_off[e], y, yd, z, a, b, zd, dgdy, dgdyd, dgdz)
    return total


@njit(**_INLINE)
def _element_derivatives(kinds, p_off, params, z_off, y, yd, z, dfdz, g, dgdy, dgdyd, dgdz, dfdp, dgdp, custom):
    """Every element's derivatives at (y, yd, z): ``(dF/dy, dF/dyd)`` summed
    over the elements; fills dF/dz, the rates g and their derivatives, and
    the parameter derivatives (see ``_dparams``)."""
    fy = 0.0
    fyd = 0.0
    for e in range(kinds.shape[0]):
        a, b = z_off[e], z_off[e + 1]
        _, dfdy_e, dfdyd_e = _force(kinds[e], params, p_off[e], p_off[e + 1], y, yd, z, a, dfdz, custom)
        fy += dfdy_e
        fyd += dfdyd_e
        if b > a:
            _rate(kinds[e], params, p_off[e], y, yd, z, a, b, g, dgdy, dgdyd, dgdz)
    _parameter_derivatives(kinds, p_off, params, z_off, y, yd, z, dfdp, dgdp)
    return fy, fyd


@njit(**_JIT)
def _parameter_derivatives(kinds, p_off, params, z_off, y, yd, z, dfdp, dgdp):
    """Every element's parameter derivatives (see ``_dparams``). Called, not
    inlined: once a step, and only with sensitivities. Inlined (every
    element kind's derivatives, at two places), the sensitivity loop's first
    compilation took 24 s instead of 14, its start's 10 s instead of 4; a
    sensitivity run (Bouc-Wen and a cubic spring, 40,000 steps, best of 40)
    takes 25.8 ms against 24.6 ms, inside this machine's noise."""
    for e in range(kinds.shape[0]):
        _dparams(kinds[e], params, p_off[e], p_off[e + 1], y, yd, z, z_off[e], z_off[e + 1], dfdp, dgdp)


@njit(**_INLINE)
def _parameter_term(pi, ydd, yd, y, dfdp):
    """Explicit derivative of the equation of motion's residual by the
    physical parameter ``pi`` (0, 1, 2: mass, damping, stiffness; 3 + i:
    the elements' ``params[i]``; -1: none, a direction of the state)."""
    if pi == 0:
        return ydd
    if pi == 1:
        return yd
    if pi == 2:
        return y
    if pi >= 3:
        return dfdp[pi - 3]
    return 0.0


@njit(**_INLINE)
def _rate_tangents(s, pi, nz, dgdy, dgdyd, dgdz, dgdp):
    """The internal states' rates' sensitivities in the direction ``s``
    (moving parameter ``pi``), from those of y, yd and z already in ``s``."""
    for j in range(nz):
        rate = dgdy[j] * s[STATE_Y] + dgdyd[j] * s[STATE_YD]
        for col in range(nz):
            rate += dgdz[j, col] * s[STATE_Z + col]
        if pi >= 3:
            rate += dgdp[j, pi - 3]
        s[STATE_Z + nz + j] = rate


@njit(**_INLINE)
def _initial_tangents(tangents, param_of, y, yd, ydd, z, m, c, k, kinds, p_off, params, z_off,
                      dfdz, g, dgdy, dgdyd, dgdz, dfdp, dgdp, custom):
    """The acceleration's and the rates' sensitivities at a start in
    equilibrium (``init_accel``, its acceleration ``ydd``), from those of
    (y, yd, z)."""
    nz = z.shape[0]
    fy, fyd = _element_derivatives(kinds, p_off, params, z_off, y, yd, z, dfdz, g, dgdy, dgdyd, dgdz, dfdp, dgdp,
                                   custom)
    for d in range(tangents.shape[0]):
        s = tangents[d]
        pi = param_of[d]
        moved = (c + fyd) * s[STATE_YD] + (k + fy) * s[STATE_Y] + _parameter_term(pi, ydd, yd, y, dfdp)
        for j in range(nz):
            moved += dfdz[j] * s[STATE_Z + j]
        s[STATE_YDD] = -moved / m
        _rate_tangents(s, pi, nz, dgdy, dgdyd, dgdz, dgdp)


@njit(**_INLINE)
def _tangent_step(tangents, param_of, y1, yd1, ydd1, z1, h, m, c, k, kinds, p_off, params, z_off,
                  dfdz, g, dgdy, dgdyd, dgdz, dfdp, dgdp, a_mat, pivots, x, custom):
    """Carry the sensitivities (``tangents``, a row per direction laid out
    as the state) over the step that has just converged at (y1, z1): the
    step's equations differentiated at their solution, one linear solve
    with the Newton matrix per direction."""
    nz = z1.shape[0]
    n = 1 + nz
    c_acc, c_vel, jac_lin = _newmark_constants(h, m, c, k)
    half_h = 0.5 * h
    fy, fyd = _element_derivatives(kinds, p_off, params, z_off, y1, yd1, z1, dfdz, g, dgdy, dgdyd, dgdz,
                                   dfdp, dgdp, custom)
    a_mat[0, 0] = jac_lin + fy + fyd * c_vel
    for j in range(nz):
        a_mat[0, 1 + j] = dfdz[j]
        a_mat[1 + j, 0] = -half_h * (dgdy[j] + dgdyd[j] * c_vel)
        for col in range(nz):
            a_mat[1 + j, 1 + col] = -half_h * dgdz[j, col]
        a_mat[1 + j, 1 + j] += 1.0
    if n > 1:
        _factor_inplace(a_mat, pivots, n)
    for d in range(tangents.shape[0]):
        s = tangents[d]
        pi = param_of[d]
        # the parts of yd1's and ydd1's sensitivities set by the last state
        dyd_last = -c_vel * s[STATE_Y] - s[STATE_YD]
        dydd_last = -c_acc * (s[STATE_Y] + h * s[STATE_YD]) - s[STATE_YDD]
        x[0] = -(m * dydd_last + (c + fyd) * dyd_last + _parameter_term(pi, ydd1, yd1, y1, dfdp))
        for j in range(nz):
            x[1 + j] = s[STATE_Z + j] + half_h * (s[STATE_Z + nz + j] + dgdyd[j] * dyd_last)
            if pi >= 3:
                x[1 + j] += half_h * dgdp[j, pi - 3]
        if n == 1:
            x[0] /= a_mat[0, 0]
        else:
            _solve_factored(a_mat, pivots, x, n)
        s[STATE_Y] = x[0]
        s[STATE_YD] = c_vel * x[0] + dyd_last
        s[STATE_YDD] = c_acc * x[0] + dydd_last
        for j in range(nz):
            s[STATE_Z + j] = x[1 + j]
        _rate_tangents(s, pi, nz, dgdy, dgdyd, dgdz, dgdp)


@njit(**_INLINE)
def _newmark_constants(h, m, c, k):
    """The factors of a step of length ``h``: the acceleration's and the
    velocity's by the displacement's change, and the linear part of the
    Newton matrix."""
    c_acc = 4.0 / (h * h)
    c_vel = 2.0 / h
    return c_acc, c_vel, m * c_acc + c * c_vel + k


@njit(**_INLINE)
def _end_rates(q, y, yd, ydd, h, c_vel, c_acc):
    """Velocity and acceleration at a step's end whose displacement is
    ``q`` (Newmark's average acceleration from ``y, yd, ydd``)."""
    return c_vel * (q - y) - yd, c_acc * (q - y - h * yd) - ydd


# --------------------------------------------------------------------------
# Integrator
# --------------------------------------------------------------------------
@njit(**_LOOP)
def _stateless_run(u, n_steps, h, m, c, k, kinds, p_off, params, y, yd, ydd, peak, y_out, yd_out, rtol, max_iter,
                   no_z, dfdz, custom):
    """``newmark_run`` without internal states or sensitivities: the same
    operations in the same order on scalars (bit-identical results), as the
    array bookkeeping of the general loop cost more than the arithmetic
    (a linear step took 64 ns there, 31 ns here; a cubic spring's 107 ns
    and 59 ns: ``benchmarks/bench_integrator_step.py``)."""
    n_u = u.shape[0]
    n_out = y_out.shape[0]
    c_acc, c_vel, jac_lin = _newmark_constants(h, m, c, k)
    n_failed = 0
    n_iter = 0
    for i in range(n_steps + 1):
        if i < n_out:
            y_out[i] = y
            yd_out[i] = yd
        if i == n_steps:
            break
        u1 = u[(i + 1) % n_u]
        q = y + h * yd + 0.25 * h * h * ydd
        converged = False
        for it in range(max_iter):
            n_iter += 1
            yd1, ydd1 = _end_rates(q, y, yd, ydd, h, c_vel, c_acc)
            res = m * ydd1 + c * yd1 + k * q - u1
            jac = jac_lin
            for e in range(kinds.shape[0]):
                f, dfdy, dfdyd = _force(kinds[e], params, p_off[e], p_off[e + 1], q, yd1, no_z, 0, dfdz, custom)
                res += f
                jac += dfdy + dfdyd * c_vel
            step = -res / jac
            q += step
            if not np.isfinite(q):
                break
            if abs(step) <= rtol * max(abs(q), peak):
                converged = True
                break
        if not converged:
            n_failed += 1
        yd1, ydd = _end_rates(q, y, yd, ydd, h, c_vel, c_acc)
        y = q
        yd = yd1
        peak = max(peak, abs(y))
    return y, yd, ydd, n_failed, n_iter


@njit(**_LOOP)
def _one_state_run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, y, yd, ydd, z, zd, y_out, yd_out, z_out,
                   rtol, max_iter, zq, dfdz, g, dgdy, dgdyd, dgdz, custom):
    """``newmark_run`` with one internal state and no sensitivities (a
    hysteresis, a stiffness drift's clock, a series damper, with any
    stateless elements): the 2 x 2 Newton step of the general loop on
    scalars, the same operations in the same order (bit-identical
    results).  In the general loop every access to the Newton matrix and
    residual was a load or a store the compiler could not keep in
    registers (a Bouc-Wen step took 284 ns there, 218 ns here)."""
    n_u = u.shape[0]
    n_out = y_out.shape[0]
    c_acc, c_vel, jac_lin = _newmark_constants(h, m, c, k)
    peak_y = abs(y)
    peak_z = abs(z[0])
    n_failed = 0
    n_iter = 0
    for i in range(n_steps + 1):
        if i < n_out:
            y_out[i] = y
            yd_out[i] = yd
            z_out[i, 0] = z[0]
        if i == n_steps:
            break
        u1 = u[(i + 1) % n_u]
        q0 = y + h * yd + 0.25 * h * h * ydd
        q1 = z[0] + 0.5 * h * zd[0]
        converged = False
        for it in range(max_iter):
            n_iter += 1
            yd1, ydd1 = _end_rates(q0, y, yd, ydd, h, c_vel, c_acc)
            r0 = m * ydd1 + c * yd1 + k * q0 - u1
            r1 = 0.0
            j00 = jac_lin
            j01 = 0.0
            j10 = 0.0
            j11 = 0.0
            zq[0] = q1
            for e in range(kinds.shape[0]):
                a, b = z_off[e], z_off[e + 1]
                f, dfdy, dfdyd = _force(kinds[e], params, p_off[e], p_off[e + 1], q0, yd1, zq, a, dfdz, custom)
                r0 += f
                j00 += dfdy + dfdyd * c_vel
                if b > a:
                    j01 = dfdz[0]
                    _rate(kinds[e], params, p_off[e], q0, yd1, zq, a, b, g, dgdy, dgdyd, dgdz)
                    r1 = q1 - z[0] - 0.5 * h * (zd[0] + g[0])
                    j10 = -0.5 * h * (dgdy[0] + dgdyd[0] * c_vel)
                    j11 = -0.5 * h * dgdz[0, 0]
                    j11 += 1.0
            r0 = -r0
            r1 = -r1
            # _solve2_inplace on scalars
            if abs(j10) > abs(j00):
                a00, a01, b0, a10, a11, b1 = j10, j11, r1, j00, j01, r0
            else:
                a00, a01, b0, a10, a11, b1 = j00, j01, r0, j10, j11, r1
            f = a10 / a00
            if f != 0.0:
                a11 -= f * a01
                b1 -= f * b0
            x1 = b1 / a11
            x0 = (b0 - a01 * x1) / a00
            q0 += x0
            q1 += x1
            if not (np.isfinite(q0) and np.isfinite(q1)):
                break
            if abs(x0) <= rtol * max(abs(q0), peak_y) and abs(x1) <= rtol * max(abs(q1), peak_z):
                converged = True
                break
        if not converged:
            n_failed += 1
        yd1, ydd = _end_rates(q0, y, yd, ydd, h, c_vel, c_acc)
        y = q0
        yd = yd1
        z[0] = q1
        # Rates at the converged point, as the next step's trapezoid needs.
        _total_force_and_rates(kinds, p_off, params, z_off, y, yd, z, zd, dfdz, dgdy, dgdyd, dgdz, custom)
        peak_y = max(peak_y, abs(y))
        peak_z = max(peak_z, abs(z[0]))
    return y, yd, ydd, n_failed, n_iter


@njit(**_LOOP)
def _two_state_run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, y, yd, ydd, z, zd, y_out, yd_out, z_out,
                   rtol, max_iter, zq, dfdz, g, dgdy, dgdyd, dgdz, custom):
    """``newmark_run`` with two internal states and no sensitivities (a
    second mode, or two elements of one state each, with any stateless
    elements): the 3 x 3 Newton step of the general loop on scalars, the
    same operations in the same order (bit-identical results), for the
    reason of ``_one_state_run`` (a second mode's step took 288 ns in the
    general loop)."""
    n_u = u.shape[0]
    n_out = y_out.shape[0]
    c_acc, c_vel, jac_lin = _newmark_constants(h, m, c, k)
    half_h = 0.5 * h
    # the Newton matrix couples the two states only inside one element
    one_element = False
    for e in range(kinds.shape[0]):
        if z_off[e + 1] - z_off[e] == 2:
            one_element = True
    peak_y = abs(y)
    peak_z0 = abs(z[0])
    peak_z1 = abs(z[1])
    n_failed = 0
    n_iter = 0
    for i in range(n_steps + 1):
        if i < n_out:
            y_out[i] = y
            yd_out[i] = yd
            z_out[i, 0] = z[0]
            z_out[i, 1] = z[1]
        if i == n_steps:
            break
        u1 = u[(i + 1) % n_u]
        q0 = y + h * yd + 0.25 * h * h * ydd
        q1 = z[0] + half_h * zd[0]
        q2 = z[1] + half_h * zd[1]
        converged = False
        for it in range(max_iter):
            n_iter += 1
            yd1, ydd1 = _end_rates(q0, y, yd, ydd, h, c_vel, c_acc)
            r0 = m * ydd1 + c * yd1 + k * q0 - u1
            j00 = jac_lin
            zq[0] = q1
            zq[1] = q2
            for e in range(kinds.shape[0]):
                a, b = z_off[e], z_off[e + 1]
                f, dfdy, dfdyd = _force(kinds[e], params, p_off[e], p_off[e + 1], q0, yd1, zq, a, dfdz, custom)
                r0 += f
                j00 += dfdy + dfdyd * c_vel
                if b > a:
                    _rate(kinds[e], params, p_off[e], q0, yd1, zq, a, b, g, dgdy, dgdyd, dgdz)
            r1 = q1 - z[0] - half_h * (zd[0] + g[0])
            r2 = q2 - z[1] - half_h * (zd[1] + g[1])
            j10 = -half_h * (dgdy[0] + dgdyd[0] * c_vel)
            j20 = -half_h * (dgdy[1] + dgdyd[1] * c_vel)
            j11 = -half_h * dgdz[0, 0]
            j11 += 1.0
            j22 = -half_h * dgdz[1, 1]
            j22 += 1.0
            j12 = -half_h * dgdz[0, 1] if one_element else 0.0
            j21 = -half_h * dgdz[1, 0] if one_element else 0.0
            x0, x1, x2 = _solve3(j00, dfdz[0], dfdz[1], j10, j11, j12, j20, j21, j22, -r0, -r1, -r2)
            q0 += x0
            q1 += x1
            q2 += x2
            if not (np.isfinite(q0) and np.isfinite(q1) and np.isfinite(q2)):
                break
            if (abs(x0) <= rtol * max(abs(q0), peak_y) and abs(x1) <= rtol * max(abs(q1), peak_z0)
                    and abs(x2) <= rtol * max(abs(q2), peak_z1)):
                converged = True
                break
        if not converged:
            n_failed += 1
        yd1, ydd = _end_rates(q0, y, yd, ydd, h, c_vel, c_acc)
        y = q0
        yd = yd1
        z[0] = q1
        z[1] = q2
        # Rates at the converged point, as the next step's trapezoid needs.
        _total_force_and_rates(kinds, p_off, params, z_off, y, yd, z, zd, dfdz, dgdy, dgdyd, dgdz, custom)
        peak_y = max(peak_y, abs(y))
        peak_z0 = max(peak_z0, abs(z[0]))
        peak_z1 = max(peak_z1, abs(z[1]))
    return y, yd, ydd, n_failed, n_iter


@njit(**_JIT)
def _equilibrium_start(u0, m, c, k, kinds, p_off, params, z_off, state, custom):
    """Set the carried state's acceleration (and its internal states' rates)
    to equilibrium of the equation of motion at t = 0 (``init_accel``)."""
    nz = z_off[z_off.shape[0] - 1]
    z = state[STATE_Z:STATE_Z + nz].copy()
    zd = state[STATE_Z + nz:STATE_Z + 2 * nz].copy()
    dfdz = np.zeros(nz)
    dgdy = np.zeros(nz)
    dgdyd = np.zeros(nz)
    dgdz = np.zeros((nz, nz))
    y, yd = state[STATE_Y], state[STATE_YD]
    ftot = _total_force_and_rates(kinds, p_off, params, z_off, y, yd, z, zd, dfdz, dgdy, dgdyd, dgdz, custom)
    state[STATE_YDD] = (u0 - c * yd - k * y - ftot) / m
    for j in range(nz):  # a loop: a slice assignment compiles its shape checks (seconds)
        state[STATE_Z + nz + j] = zd[j]


@njit(**_JIT)
def _equilibrium_tangents(tangents, param_of, m, c, k, kinds, p_off, params, z_off, state, custom):
    """The sensitivities' accelerations and rates at a start in equilibrium
    (after :func:`_equilibrium_start`)."""
    nz = z_off[z_off.shape[0] - 1]
    _initial_tangents(tangents, param_of, state[STATE_Y], state[STATE_YD], state[STATE_YDD],
                      state[STATE_Z:STATE_Z + nz].copy(), m, c, k, kinds, p_off, params, z_off,
                      np.zeros(nz), np.zeros(nz), np.zeros(nz), np.zeros(nz), np.zeros((nz, nz)),
                      np.zeros(params.shape[0]), np.zeros((nz, params.shape[0])), custom)


def newmark_run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, state,
                init_accel, y_out, yd_out, z_out, rtol, max_iter, tangents, param_of, dy_out, custom):
    """Integrate ``n_steps`` steps of length ``h`` from ``state`` (updated in place).

    Step ``i`` goes from time ``i h`` to ``(i + 1) h`` with input
    ``u[(i + 1) % len(u)]`` (so a periodic input of one period can be run
    period after period).  Sample ``i`` of the outputs is the state at time
    ``i h`` (only the first ``len(y_out)`` samples are stored).

    Sensitivities (none when ``tangents`` has no rows): each row of
    ``tangents`` is the derivative of the state (same layout) along one
    direction, updated in place; ``param_of`` says which physical parameter
    the direction moves (0, 1, 2: mass, damping, stiffness; ``3 + i``:
    ``params[i]``; -1: none, a direction of the initial state), and
    ``dy_out[i, d]`` receives the displacement's derivative at sample ``i``.
    They are the exact derivatives of the discrete scheme (its equations
    differentiated at each converged step), so a fit's Jacobian costs one
    simulation instead of one per parameter.

    ``custom`` calls the oscillator's custom elements by slot, None when it
    has none (see :func:`custom_dispatcher`).

    The loop a call needs is chosen here, in Python, so that only that one
    is compiled: dispatched inside one compiled function, the first Bouc-Wen
    simulation of a fresh install compiled all four loops (39 s; its own
    loop and start take about 10 s). The dispatch costs about 25 us a call,
    below the noise of a period's simulation.

    Returns
    -------
    n_failed : int
        Steps where Newton did not reach ``rtol`` within ``max_iter``.
    n_iter : int
        Total Newton iterations (diagnostics).
    """
    nz = int(z_off[-1])
    n_dir = tangents.shape[0]
    if init_accel:
        _equilibrium_start(u[0], m, c, k, kinds, p_off, params, z_off, state, custom)
        if n_dir > 0:
            _equilibrium_tangents(tangents, param_of, m, c, k, kinds, p_off, params, z_off, state, custom)
    y, yd, ydd = float(state[STATE_Y]), float(state[STATE_YD]), float(state[STATE_YDD])
    z = state[STATE_Z:STATE_Z + nz].copy()
    zd = state[STATE_Z + nz:STATE_Z + 2 * nz].copy()
    # the loops' work arrays (they are compiled without reference counting
    # and allocate nothing)
    zq, dfdz, g, dgdy, dgdyd = (np.zeros(nz) for _ in range(5))
    dgdz = np.zeros((nz, nz))
    if n_dir == 0 and nz <= 2:
        if nz == 0:
            y, yd, ydd, n_failed, n_iter = _stateless_run(u, n_steps, h, m, c, k, kinds, p_off, params, y, yd, ydd,
                                                          abs(y), y_out, yd_out, rtol, max_iter, zq, dfdz, custom)
        else:
            run = _one_state_run if nz == 1 else _two_state_run
            y, yd, ydd, n_failed, n_iter = run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, y, yd, ydd, z, zd,
                                               y_out, yd_out, z_out, rtol, max_iter, zq, dfdz, g, dgdy, dgdyd, dgdz,
                                               custom)
        state[STATE_Y] = y
        state[STATE_YD] = yd
        state[STATE_YDD] = ydd
        state[STATE_Z:STATE_Z + nz] = z
        state[STATE_Z + nz:STATE_Z + 2 * nz] = zd
        return n_failed, n_iter
    n = 1 + nz
    return _general_run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, state, y, yd, ydd, z, zd, y_out,
                        yd_out, z_out, rtol, max_iter, tangents, param_of, dy_out, np.zeros(n), np.zeros(n),
                        np.zeros((n, n)), np.zeros(n), dfdz, g, dgdy, dgdyd, dgdz, zq,
                        np.zeros(params.shape[0]), np.zeros((nz, params.shape[0])), np.zeros((n, n)),
                        np.zeros(n, dtype=np.int64), np.zeros(n), custom)


@njit(**_LOOP)
def _general_run(u, n_steps, h, m, c, k, kinds, p_off, params, z_off, state, y, yd, ydd, z, zd, y_out, yd_out, z_out,
                 rtol, max_iter, tangents, param_of, dy_out, q, res, jac, peak, dfdz, g, dgdy, dgdyd, dgdz, zq, dfdp,
                 dgdp, a_mat, pivots, x, custom):
    """The loop of :func:`newmark_run` for any number of states, with
    sensitivities, on the work arrays it made."""
    nz = z_off[z_off.shape[0] - 1]
    n = 1 + nz
    n_u = u.shape[0]
    n_out = y_out.shape[0]
    n_dir = tangents.shape[0]
    n_dy = dy_out.shape[0]
    peak[0] = abs(y)
    for j in range(nz):
        peak[1 + j] = abs(z[j])

    c_acc, c_vel, jac_lin = _newmark_constants(h, m, c, k)
    n_failed = 0
    n_iter = 0

    for i in range(n_steps + 1):
        if i < n_out:
            y_out[i] = y
            yd_out[i] = yd
            for j in range(nz):
                z_out[i, j] = z[j]
        if i < n_dy:
            for d in range(n_dir):
                dy_out[i, d] = tangents[d, STATE_Y]
        if i == n_steps:
            break
        u1 = u[(i + 1) % n_u]

        # Predictor: ydd_{n+1} = 0 and zd_{n+1} = 0.
        q[0] = y + h * yd + 0.25 * h * h * ydd
        for j in range(nz):
            q[1 + j] = z[j] + 0.5 * h * zd[j]

        converged = False
        for it in range(max_iter):
            n_iter += 1
            y1 = q[0]
            yd1, ydd1 = _end_rates(y1, y, yd, ydd, h, c_vel, c_acc)
            for r in range(n):
                for j in range(n):
                    jac[r, j] = 0.0
            res[0] = m * ydd1 + c * yd1 + k * y1 - u1
            jac[0, 0] = jac_lin
            for j in range(nz):
                zq[j] = q[1 + j]
            for e in range(kinds.shape[0]):
                a, b = z_off[e], z_off[e + 1]
                f, dfdy, dfdyd = _force(kinds[e], params, p_off[e], p_off[e + 1], y1, yd1, zq, a, dfdz, custom)
                res[0] += f
                jac[0, 0] += dfdy + dfdyd * c_vel
                for j in range(a, b):
                    jac[0, 1 + j] = dfdz[j]
                if b > a:
                    _rate(kinds[e], params, p_off[e], y1, yd1, zq, a, b, g, dgdy, dgdyd, dgdz)
                    for j in range(a, b):
                        res[1 + j] = q[1 + j] - z[j] - 0.5 * h * (zd[j] + g[j])
                        jac[1 + j, 0] = -0.5 * h * (dgdy[j] + dgdyd[j] * c_vel)
                        for col in range(a, b):
                            jac[1 + j, 1 + col] = -0.5 * h * dgdz[j, col]
                        jac[1 + j, 1 + j] += 1.0
            for j in range(n):
                res[j] = -res[j]
            if n == 1:
                res[0] /= jac[0, 0]
            elif n == 2:
                _solve2_inplace(jac, res)
            else:
                _factor_inplace(jac, pivots, n)
                _solve_factored(jac, pivots, res, n)
            ok = True
            finite = True
            for j in range(n):
                q[j] += res[j]
                if not np.isfinite(q[j]):
                    finite = False
                scale = max(abs(q[j]), peak[j])
                if abs(res[j]) > rtol * scale:
                    ok = False
            if not finite:
                break
            if ok:
                converged = True
                break
        if not converged:
            n_failed += 1

        y1 = q[0]
        yd1, ydd = _end_rates(y1, y, yd, ydd, h, c_vel, c_acc)
        y = y1
        yd = yd1
        for j in range(nz):
            z[j] = q[1 + j]
        if n_dir > 0:
            _tangent_step(tangents, param_of, y, yd, ydd, z, h, m, c, k, kinds, p_off, params, z_off,
                          dfdz, g, dgdy, dgdyd, dgdz, dfdp, dgdp, a_mat, pivots, x, custom)
        if nz > 0:
            # Rates at the converged point, as the next step's trapezoid needs.
            _total_force_and_rates(kinds, p_off, params, z_off, y, yd, z, zd,
                                   dfdz, dgdy, dgdyd, dgdz, custom)
        peak[0] = max(peak[0], abs(y))
        for j in range(nz):
            peak[1 + j] = max(peak[1 + j], abs(z[j]))

    state[STATE_Y] = y
    state[STATE_YD] = yd
    state[STATE_YDD] = ydd
    for j in range(nz):
        state[STATE_Z + j] = z[j]
        state[STATE_Z + nz + j] = zd[j]
    return n_failed, n_iter


@njit(**_JIT)
def stateless_forces(kinds, p_off, params, z_off, y, yd, custom):
    """Total force of the elements without internal states at each sample
    of a motion ``(y, yd)`` (elements with states are skipped)."""
    out = np.zeros(y.shape[0])
    dfdz = np.zeros(1)
    empty = np.zeros(0)
    for e in range(kinds.shape[0]):
        if z_off[e + 1] > z_off[e]:
            continue
        for i in range(y.shape[0]):
            f, _, _ = _force(kinds[e], params, p_off[e], p_off[e + 1], y[i], yd[i], empty, 0, dfdz, custom)
            out[i] += f
    return out
