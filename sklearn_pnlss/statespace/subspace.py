"""Frequency-domain subspace identification of a linear state-space model
from FRF data, weighted by the FRF variance, and its refinement by a weighted
nonlinear least-squares fit.

By default both work on a warped frequency axis. Lines crowded on a short
arc of the unit circle (the F-16's 2-15 Hz at 400 Hz: 0.03-0.24 rad) make
the powers z^0 .. z^(q-1) of the subspace step nearly collinear and put the
poles within 1e-3 of the circle, where a least-squares step easily throws
one outside. The
all-pass (Moebius) map zeta = (z - a) / (1 - a z), a real in (-1, 1), maps
the unit circle and the unit disc onto themselves; it spreads the band over
the circle (its geometric centre in tan(angle / 2) goes to a quarter turn)
and stretches the distances of the poles to the circle by as much. A model
of order n in zeta is exactly one of order n in z (:func:`warp_model`), with
the same stability, so the fit is done in zeta and converted back.

References: McKelvey, Akcay & Ljung (1996), "Subspace-based multivariable
system identification from frequency response data", IEEE TAC 41(7);
Pintelon (2002), "Frequency-domain subspace system identification using
non-parametric noise models", Automatica 38(8); on the frequency warping by
an all-pass map, Oppenheim & Johnson (1972), "Discrete representation of
signals", Proc. IEEE 60(6).
"""
import numpy as np
from scipy.linalg import qr, sqrtm, svd

from ..utils.memo import last_results
from .levenberg_marquardt import levenberg_marquardt
from .linear import is_stable, peak_gain, resolvent_products, stabilize

__all__ = ["fd_subspace", "fd_refine", "frf_weights", "band_warp", "warp_model"]

# The warp is capped so that zeta stays well defined (|a| < 1) and the
# conversion (I + a A)^-1 stays well conditioned.
_MAX_WARP = 0.98


def band_warp(z):
    """Parameter ``a`` of the all-pass map that spreads the lines ``z``
    over the unit circle.

    With ``t = tan(angle / 2)``, the map ``zeta = (z - a) / (1 - a z)``
    multiplies ``t`` by ``k = (1 + a) / (1 - a)``; ``k`` is chosen so that
    the geometric mean of ``t`` over the band's first and last line goes to
    1 (a quarter turn). A band that already spans the circle gets ``a``
    near 0. Capped at ``|a| <= 0.98``.

    Parameters
    ----------
    z : ndarray of complex, points on the unit circle

    Returns
    -------
    a : float
    """
    angle = np.abs(np.angle(np.asarray(z)))
    angle = angle[(angle > 0) & (angle < np.pi)]
    if angle.size == 0:
        return 0.0
    t = np.tan(angle / 2)
    k = 1.0 / np.sqrt(t.min() * t.max())
    return float(np.clip((k - 1) / (k + 1), -_MAX_WARP, _MAX_WARP))


def _resolve_warp(warp, z):
    if warp is None:
        return 0.0
    if isinstance(warp, str):
        if warp != "auto":
            raise ValueError(f"warp must be 'auto', None or a number in (-1, 1); got {warp!r}.")
        return band_warp(z)
    a = float(warp)
    if not -1.0 < a < 1.0:
        raise ValueError(f"warp must be 'auto', None or a number in (-1, 1); got {warp!r}.")
    return a


def warp_model(A, B, C, D, a):
    """A model in ``zeta = (z - a) / (1 - a z)`` as the same model in ``z``.

    ``G(z) = D + C (zI - A)^-1 B`` equals ``Dw + Cw (zeta I - Aw)^-1 Bw``
    with ``M = I + a Aw``: ``A = M^-1 (Aw + a I)``, ``B = s M^-1 Bw``,
    ``C = s Cw M^-1``, ``D = Dw - a Cw M^-1 Bw``, ``s = sqrt(1 - a^2)``.
    The eigenvalues map by the inverse all-pass, so stability is kept;
    ``warp_model(..., -a)`` is the inverse conversion (z to zeta).

    Parameters
    ----------
    A, B, C, D : ndarray
        The model in ``zeta``.
    a : float in (-1, 1)

    Returns
    -------
    A, B, C, D : ndarray
        The model in ``z``.
    """
    if a == 0.0:
        return A, B, C, D
    n = A.shape[0]
    M = np.eye(n) + a * A
    MA = np.linalg.solve(M, np.concatenate([A + a * np.eye(n), B], axis=1))
    CM = np.linalg.solve(M.T, C.T).T
    s = np.sqrt(1.0 - a * a)
    return MA[:, :n], s * MA[:, n:], s * CM, D - a * CM @ B


def frf_weights(G, var):
    """Per-line weights ``1/sigma`` from FRF variances (K, p, m).

    Residuals weighted this way have unit variance. Lines without a usable variance (zero, NaN) get the median weight so a
    noiseless simulation does not produce infinite weights.

    The last few are kept (read-only): a BLA's fit asks for the same
    weights at each of its subspace fits, refinements and comparisons
    (eighteen times on Bouc-Wen), and their medians cost a fifth of a
    millisecond each.
    """
    return _frf_weights(np.asarray(G, dtype=complex), None if var is None else np.asarray(var, dtype=float))


@last_results(maxsize=4)
def _frf_weights(G, var):
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


def _estimate_bd(A, C, G, z, w, estimate_d=True, a=0.0):
    """Weighted linear least squares for B and D given A and C.

    ``z`` are the (warped) points the model ``A, C`` lives on. Without
    ``estimate_d`` the direct term of the model in the original variable must
    vanish: ``D = a C (I + a A)^-1 B`` (see :func:`warp_model`), linear in B.
    """
    K, p, m = G.shape
    n = A.shape[0]
    # C (zI - A)^-1, shape (K, p, n)
    _, CP = resolvent_products(A, z, C=C)
    if not estimate_d and a != 0.0:
        CM = np.linalg.solve((np.eye(n) + a * A).T, C.T).T
        CP = CP + a * CM
    # vec(CP B + D) = (I_m kron CP) vec(B) + (I_m kron I_p) vec(D)
    M = np.einsum("bc,kai->kbaci", np.eye(m), CP).reshape(K, m * p, m * n)  # I_m kron CP per line
    if estimate_d:
        M = np.concatenate([M, np.broadcast_to(np.eye(p * m), (K, p * m, p * m))], axis=2)
    rhs = G.transpose(0, 2, 1).reshape(K, p * m)  # column-major vec per line
    M = M * w[:, None, None]
    rhs = rhs * w[:, None]
    Mr = np.concatenate([M.real.reshape(-1, M.shape[2]), M.imag.reshape(-1, M.shape[2])])
    rr = np.concatenate([rhs.real.ravel(), rhs.imag.ravel()])
    theta = np.linalg.lstsq(Mr, rr, rcond=None)[0]
    B = theta[: n * m].reshape(m, n).T
    if estimate_d:
        D = theta[n * m :].reshape(m, p).T
    elif a != 0.0:
        D = a * CM @ B
    else:
        D = np.zeros((p, m))
    return B, D


def fd_subspace(G, z, n_states, *, var=None, q=None, estimate_d=True, warp="auto"):
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
    warp : "auto", float or None, default="auto"
        Parameter ``a`` of the all-pass frequency warping the identification
        works in (see the module docstring): ``"auto"`` spreads the band over
        the circle (:func:`band_warp`), None or 0 works on ``z`` itself.

    Returns
    -------
    A, B, C, D : ndarray
        A stable discrete-time model in ``z`` (unstable poles are
        reflected).
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
    a = _resolve_warp(warp, z)
    z = (z - a) / (1 - a * z)
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
    B, D = _estimate_bd(A, C, G, z, w, estimate_d, a)
    A, B, C, D = warp_model(A, B, C, D, a)
    if not estimate_d:
        D = np.zeros_like(D)  # zero up to rounding by construction
    return A, B, C, D


def _pull_inside(A, radius):
    """A with its eigenvalues beyond ``radius`` moved radially onto it (the
    others kept); all scaled by one factor when A is too close to defective
    for its eigenvectors to be trusted."""
    lam, V = np.linalg.eig(A)
    outside = np.abs(lam) > radius
    if np.linalg.cond(V) < 1e8:
        lam = np.where(outside, lam / np.abs(lam) * radius, lam)
        moved = V @ np.diag(lam) @ np.linalg.inv(V)
        if np.max(np.abs(moved.imag)) <= 1e-8 * max(np.max(np.abs(moved.real)), 1e-300):
            moved = moved.real
            if np.all(np.abs(np.linalg.eigvals(moved)) <= radius * (1 + 1e-12)):
                return moved * (1 - 1e-12)
    return A * (radius / np.max(np.abs(lam))) * (1 - 1e-12)


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


def _frf_jacobian(CP, PB, w, estimate_d, tie=None):
    """The Jacobian of the weighted FRF residual of :func:`fd_refine` in
    ``A, B, C`` (and ``D`` with ``estimate_d``), rows ``[real; imag]`` of
    each line's (p, m) entries: dG_ab/dA_ij = CP_ai PB_jb, dG_ab/dB_ij =
    CP_ai d_jb, dG_ab/dC_ij = d_ai PB_jb, dG_ab/dD_ij = d_ai d_bj, times the
    line's weight ``w``. ``tie``: ``(a, C M^-1, M^-1 B)`` when the direct
    term is tied to ``D = a C M^-1 B`` (``M = I + a A``), whose derivatives
    are then added.

    Written into one real array: the B, C and D columns copied from ``CP``,
    ``PB`` and ones rather than formed as complex products with identities,
    concatenated and split into real and imaginary parts (the same numbers,
    in half the time: a tenth of the Bouc-Wen BLA's refinements)."""
    K, p, n = CP.shape
    m = PB.shape[2]
    nn, nm, pn = n * n, n * m, p * n
    J = np.zeros((2, K, p, m, nn + nm + pn + (p * m if estimate_d else 0)))
    JA = np.einsum("kai,kjb->kabij", CP, PB).reshape(K, p, m, nn)
    J[0, ..., :nn] = JA.real
    J[1, ..., :nn] = JA.imag
    for b in range(m):
        J[0, :, :, b, nn + b : nn + nm : m] = CP.real
        J[1, :, :, b, nn + b : nn + nm : m] = CP.imag
        for a in range(p):
            J[0, :, a, b, nn + nm + a * n : nn + nm + (a + 1) * n] = PB.real[:, :, b]
            J[1, :, a, b, nn + nm + a * n : nn + nm + (a + 1) * n] = PB.imag[:, :, b]
            if estimate_d:
                J[0, :, a, b, nn + nm + pn + a * m + b] = 1.0
    if tie is not None:
        a, CM, MB = tie
        J[0, ..., :nn] -= (a * a * np.einsum("ai,jb->abij", CM, MB)).reshape(p, m, nn)
        J[0, ..., nn : nn + nm] += (a * np.einsum("ai,jb->abij", CM, np.eye(m))).reshape(p, m, nm)
        J[0, ..., nn + nm : nn + nm + pn] += (a * np.einsum("ai,jb->abij", np.eye(p), MB)).reshape(p, m, pn)
    J *= w[None, :, None, None, None]
    return J.reshape(2 * K * p * m, -1)


def fd_refine(A, B, C, D, G, z, *, var=None, estimate_d=True, max_iter=100, warp="auto",
              stability_margin=0.0, bound_points=None, bound=None, stay_stable=True):
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
    Jacobian evaluations.

    The fit runs on the warped axis of :func:`fd_subspace` (``warp``, same
    meaning), where lightly damped poles sit further from the unit circle.
    From a stable start, a step that would make the model unstable counts as
    a failed step (LM then shortens it), so the iterates stay stable: an FRF
    on the circle can be fitted about as well by a pole just outside it, and
    a fit that crossed would otherwise be lost whole (``stay_stable=False``
    leaves the steps free, the earlier behaviour). With
    ``stability_margin`` the poles (in ``z``) are kept within radius
    ``1 - stability_margin`` in the same way; a stable start with poles
    beyond that radius has them first moved onto it (radially). A refined
    model that is unstable or fits worse is discarded and the (so moved)
    start returned.

    ``bound_points`` (points on the unit circle outside the fitted band) and
    ``bound`` (p, m) cap the model's gain there, as failed steps too: the
    data say nothing outside the band, and a fit left free puts spare
    resonances there whose tails bend the FRF inside it, at a gain far above
    anything measured (a resonance near the Nyquist frequency +40 dB above
    the largest measured response, seen on the F-16 data), which then
    amplifies whatever the input holds there. The cap is raised to the
    start's own gain where that is higher.

    Returns
    -------
    A, B, C, D : ndarray
    """
    G = np.asarray(G, dtype=complex)
    K, p, m = G.shape
    n = A.shape[0]
    w = frf_weights(G, var)
    a = _resolve_warp(warp, z)
    zw = (z - a) / (1 - a * z)
    eye = np.eye(n)
    radius = 1.0 - float(stability_margin)
    if not is_stable(A) or not stay_stable:
        radius = None  # no constraint from an unstable start
    elif not is_stable(A, margin=stability_margin):
        A = _pull_inside(A, radius)

    def inside(Aw):
        lam = np.linalg.eigvals(Aw)
        return bool(np.all(np.abs((lam + a) / (1 + a * lam)) < radius))

    if bound_points is not None:
        bound_points = np.asarray(bound_points, dtype=complex)
        bound_w = (bound_points - a) / (1 - a * bound_points)
        with np.errstate(all="ignore"):
            try:
                start_gain = peak_gain(A, B, C, D, bound_points)
            except np.linalg.LinAlgError:
                start_gain = np.full((p, m), np.inf)
        cap = np.maximum(np.broadcast_to(np.asarray(bound, dtype=float), (p, m)), start_gain)

    def within_bound(theta):
        if bound_points is None:
            return True
        A_, B_, C_, D_ = _unpack(theta, n, m, p, estimate_d)
        if tied:
            D_ = a * C_ @ np.linalg.solve(eye + a * A_, B_)
        with np.errstate(all="ignore"):
            gain = peak_gain(A_, B_, C_, D_, bound_w)
        return bool(np.all(gain <= cap))
    # In zeta the direct term is free, or tied to D = 0 in z (fd_subspace).
    tied = not estimate_d and a != 0.0

    def residual_and_jac(theta, jacobian=True):
        A_, B_, C_, D_ = _unpack(theta, n, m, p, estimate_d)
        PB, CP = resolvent_products(A_, zw, B=B_, C=C_ if jacobian else None)  # (K,n,m), (K,p,n)
        if tied:
            Minv = np.linalg.inv(eye + a * A_)
            MB, CM = Minv @ B_, C_ @ Minv
            D_ = a * CM @ MB
        E = ((D_[None] + C_[None] @ PB - G) * w[:, None, None]).ravel()  # (K,p,m) flattened
        e = np.concatenate([E.real, E.imag])
        if not jacobian:
            return e, None
        return e, _frf_jacobian(CP, PB, w, estimate_d, (a, CM, MB) if tied else None)

    last = {}  # the last residual, by its parameters: the start's is asked for twice (here, then by LM)

    def residual(theta):
        key = theta.tobytes()
        if key not in last:
            last.clear()
            last[key] = trial_residual(theta)
        return last[key]

    def trial_residual(theta):
        if radius is not None and not inside(_unpack(theta, n, m, p, estimate_d)[0]):
            return None  # a failed step: LM shortens it
        try:
            if not within_bound(theta):
                return None
        except np.linalg.LinAlgError:
            return None
        with np.errstate(all="ignore"):
            try:
                return residual_and_jac(theta, jacobian=False)[0]
            except np.linalg.LinAlgError:  # a pole exactly on an excited line
                return None

    def normal_equations(theta):
        e, J = residual_and_jac(theta)
        return J.T @ J, J.T @ e

    Aw, Bw, Cw, Dw = warp_model(A, B, C, D, -a)
    theta0 = _pack(Aw, Bw, Cw, Dw, estimate_d)
    e0 = residual(theta0)
    if e0 is None or not np.all(np.isfinite(e0)):
        return A, B, C, D
    result = levenberg_marquardt(residual, normal_equations, theta0, n_drop=n * n, max_iter=max_iter, tol=1e-8)
    if not result.cost < e0 @ e0:
        return A, B, C, D
    A1, B1, C1, D1 = _unpack(result.theta, n, m, p, estimate_d)
    if tied:
        D1 = a * C1 @ np.linalg.solve(eye + a * A1, B1)
    A1, B1, C1, D1 = warp_model(A1, B1, C1, D1, a)
    if not estimate_d:
        D1 = np.zeros((p, m))
    if not is_stable(A1):
        return A, B, C, D
    return A1, B1, C1, D1
