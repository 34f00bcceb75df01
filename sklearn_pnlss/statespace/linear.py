"""Discrete-time linear state-space models: simulation, frequency response,
periodic steady state and modal parameters."""
import numba
import numpy as np

from ..utils.memo import last_results

__all__ = [
    "simulate_linear",
    "frequency_response",
    "peak_gain",
    "periodic_initial_state",
    "simulate_linear_signal",
    "modal_parameters",
    "is_stable",
    "stabilize",
]


@numba.njit(cache=True, nogil=True, inline="always")
def _affine(M, x, N, u, out):
    """out = M x + N u, written out.  Not imported from the PNLSS kernels'
    three-term ``_affine``: numba's on-disk cache checks only the cached
    function's own source file (see :mod:`._decoupled_kernels`)."""
    for i in range(M.shape[0]):
        acc = 0.0
        for j in range(x.shape[0]):
            acc += M[i, j] * x[j]
        for j in range(u.shape[0]):
            acc += N[i, j] * u[j]
        out[i] = acc


@numba.njit(cache=True, nogil=True)
def _lsim_kernel(A, B, C, D, U, x0):
    # Explicit loops: a small matrix product per sample (``C @ x``) allocates
    # its result, which cost 20 times the arithmetic at three states.
    Y = np.empty((U.shape[0], C.shape[0]))
    x = x0.copy()
    xn = np.empty(A.shape[0])
    for t in range(U.shape[0]):
        _affine(C, x, D, U[t], Y[t])
        _affine(A, x, B, U[t], xn)
        x[:] = xn
    return Y, x


@numba.njit(cache=True, nogil=True)
def _lsim_kernel_blas(A, B, C, D, U, x0):
    # Many states: the products by BLAS (its call costs less than the
    # arithmetic from about 32 states on).
    n_samples = U.shape[0]
    n = A.shape[0]
    Y = np.empty((n_samples, C.shape[0]))
    x = x0.copy()
    xn = np.empty(n)
    for t in range(n_samples):
        Y[t] = C @ x + D @ U[t]
        xn[:] = A @ x + B @ U[t]
        x[:] = xn
    return Y, x


# States from which the per-sample products go through BLAS (measured on
# 20,000 samples: 24 states 5.5 ms by loops against 9.7 ms by BLAS, 32
# states 9.9 against 10.9 ms, 40 states 15.2 against 11.6 ms; 3 states
# and 32,768 samples 0.5 against 11.3 ms).
_BLAS_STATES = 36


def simulate_linear(A, B, C, D, U, x0=None):
    """Simulate ``x(t+1) = A x + B u``, ``y = C x + D u`` from ``x0``.

    Parameters
    ----------
    A, B, C, D : ndarray
        State-space matrices, shapes (n, n), (n, m), (p, n), (p, m).
    U : ndarray of shape (n_samples, m)
    x0 : ndarray of shape (n,), default=None (zero state)

    Returns
    -------
    Y : ndarray of shape (n_samples, p)
    x_end : ndarray of shape (n,), the state after the last sample
    """
    A, B, C, D = (np.ascontiguousarray(M, dtype=np.float64) for M in (A, B, C, D))
    U = np.ascontiguousarray(U, dtype=np.float64)
    x0 = np.zeros(A.shape[0]) if x0 is None else np.asarray(x0, dtype=np.float64)
    kernel = _lsim_kernel_blas if A.shape[0] >= _BLAS_STATES else _lsim_kernel
    return kernel(A, B, C, D, U, x0)


# Above this condition number of A's eigenvectors, the resolvent is solved
# line by line instead of read off the eigendecomposition (whose error grows
# with it: 1e6 leaves about 1e-10 of relative error).
_EIGVEC_COND = 1e6


@last_results(maxsize=8)
def _eigen(A):
    """``(lam, V, V^-1)`` of ``A`` (read-only), or None when its
    eigenvectors are too ill conditioned to give the resolvent accurately.

    The last few are kept: a frequency-domain refinement asks for the same
    ``A`` two or three times at each of its trial models (the gain outside
    the band, the residual, its Jacobian once the trial is accepted), and
    each decomposition costs about a tenth of a millisecond of numpy's
    overhead (a fifth of the Bouc-Wen BLA's refinements)."""
    lam, V = np.linalg.eig(A)
    if not np.linalg.cond(V) < _EIGVEC_COND:
        return None
    return lam, V, np.linalg.inv(V)


def resolvent_products(A, z, B=None, C=None):
    """``(zI - A)^-1 B`` (K, n, m) and ``C (zI - A)^-1`` (K, p, n) at the
    points ``z`` (K,), each None when its matrix is.

    Through the eigendecomposition ``A = V diag(lam) V^-1`` when ``V`` is
    well conditioned: ``(zI - A)^-1 = V diag(1 / (z - lam)) V^-1`` costs
    n^2 per point instead of a solve's n^3, and runs as one matrix product
    over all points instead of K small factorisations (the BLA's refinement
    evaluates it thousands of times: 0.6 of its 1.1 s on the Bouc-Wen
    record went to batched solves). Otherwise by batched solves.
    """
    z = np.atleast_1d(np.asarray(z, dtype=complex))
    K, n = z.shape[0], A.shape[0]
    eigen = _eigen(A)
    if eigen is not None:
        lam, V, Vi = eigen
        R = 1.0 / (z[:, None] - lam[None, :])  # (K, n)
        PB = CP = None
        if B is not None:
            T = (R[:, :, None] * (Vi @ B)[None]).transpose(1, 0, 2).reshape(n, -1)  # (n, K m)
            PB = (V @ T).reshape(n, K, -1).transpose(1, 0, 2)
        if C is not None:
            CP = (((C @ V)[None] * R[:, None, :]).reshape(-1, n) @ Vi).reshape(K, -1, n)
        return PB, CP
    resolvent = z[:, None, None] * np.eye(n) - A  # (K, n, n)
    PB = None if B is None else np.linalg.solve(resolvent, np.broadcast_to(B, (K,) + B.shape))
    CP = None if C is None else np.linalg.solve(
        resolvent.transpose(0, 2, 1), np.broadcast_to(C.T, (K,) + C.T.shape)).transpose(0, 2, 1)
    return PB, CP


def frequency_response(A, B, C, D, z):
    """``G(z) = D + C (zI - A)^-1 B`` at complex points ``z``.

    Returns
    -------
    G : ndarray of shape (len(z), p, m), complex
    """
    z = np.atleast_1d(np.asarray(z, dtype=complex))
    eigen = _eigen(A)
    if eigen is None:
        PB, _ = resolvent_products(A, z, B=B)
        return D[None] + C[None] @ PB
    lam, V, Vi = eigen
    # sum_j (C V)_aj (V^-1 B)_jb / (z - lam_j): one product over all points.
    R = 1.0 / (z[:, None] - lam[None, :])
    CV, VB = C @ V, Vi @ B
    modal = (R[:, None, :, None] * CV[None, :, :, None] * VB[None, None, :, :]).sum(axis=2)
    return D[None] + modal


def peak_gain(A, B, C, D, z):
    """The largest gain ``|G(z)|`` over the points ``z``, for each output
    and input (p, m): what a bound on the gain outside the excited band is
    checked against.

    The modes' sum is one matrix product over all points, ``R M`` with
    ``R_kj = 1 / (z_k - lam_j)`` and ``M_j = (C V)_j (V^-1 B)_j``, rather
    than :func:`frequency_response`'s broadcast products summed mode by
    mode: 65 us instead of 130 at 2,048 points and three states, 0.3 ms
    instead of 2.3 at 18 states and three outputs (a BLA's refinements
    check every trial model). Its last bits may
    differ from :func:`frequency_response`'s, which does not matter for a
    gain that is only compared with a bound."""
    z = np.atleast_1d(np.asarray(z, dtype=complex))
    eigen = _eigen(A)
    if eigen is None:
        return np.max(np.abs(frequency_response(A, B, C, D, z)), axis=0)
    lam, V, Vi = eigen
    p, m = D.shape
    modes = ((C @ V)[:, :, None] * (Vi @ B)[None, :, :]).transpose(1, 0, 2).reshape(-1, p * m)  # (n, p m)
    G = (1.0 / (z[:, None] - lam[None, :])) @ modes + D.reshape(1, -1)
    return np.max(np.abs(G), axis=0).reshape(p, m)


def periodic_initial_state(A, B, C, D, U_period):
    """State at the start of a period in periodic steady state.

    One period simulated from rest ends in ``x_N``; the steady state obeys
    ``x0 = A^N x0 + x_N``, so ``x0 = (I - A^N)^-1 x_N``. Exact for a stable
    model and a periodic input.
    """
    n = A.shape[0]
    _, x_end = simulate_linear(A, B, C, D, U_period)
    AN = np.linalg.matrix_power(A, U_period.shape[0])
    return np.linalg.solve(np.eye(n) - AN, x_end)


def simulate_linear_signal(A, B, C, D, U, periodic_with=None):
    """Simulate one signal; periodic steady state when ``periodic_with`` gives
    the period length (the signal's length is a multiple of it), else from
    rest."""
    x0 = None
    if periodic_with is not None:
        x0 = periodic_initial_state(A, B, C, D, U[:periodic_with])
    return simulate_linear(A, B, C, D, U, x0)[0]


def is_stable(A, margin=0.0):
    """All eigenvalues strictly inside the circle of radius ``1 - margin``."""
    return bool(np.all(np.abs(np.linalg.eigvals(A)) < 1.0 - margin))


def stabilize(A):
    """Reflect eigenvalues outside the unit circle to ``1 / conj(lambda)``.

    The amplitude response is kept (up to a constant) while the model becomes
    stable, the usual remedy for a subspace estimate with an unstable pole.
    """
    lam, V = np.linalg.eig(A)
    outside = np.abs(lam) >= 1.0
    if not np.any(outside):
        return A
    lam = np.where(outside, 1.0 / np.conj(lam), lam)
    lam = np.where(np.abs(lam) >= 1.0, lam / np.abs(lam) * (1 - 1e-6), lam)
    return np.real(V @ np.diag(lam) @ np.linalg.inv(V))


def modal_parameters(A, fs):
    """Natural frequencies (Hz) and damping ratios of the poles of ``A``.

    Discrete poles ``z`` map to ``s = fs log z``; each complex pair appears
    once (positive imaginary part), real poles have damping 1 (or more for
    ``z`` on the negative axis this mapping is only indicative).

    Returns
    -------
    frequencies : ndarray, Hz, sorted
    damping : ndarray, same order
    """
    z = np.linalg.eigvals(A)
    z = z[np.imag(z) >= -1e-12]
    s = fs * np.log(z.astype(complex))
    wn = np.abs(s)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(wn > 0, -np.real(s) / wn, 1.0)
    order = np.argsort(wn)
    return wn[order] / (2 * np.pi), zeta[order]
