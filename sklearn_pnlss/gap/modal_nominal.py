"""A structure's modes read off measured data: the nominal of a structure
that has only test data (a ground vibration test, a shaker on a frame).

The frequency response from the force to every sensor is fitted by a modal
model, poles by nonlinear least squares (started from the library's
frequency-domain subspace) and, for given poles, the residues by linear
least squares (least-squares frequency-domain modal analysis).  The
residues of the sensor at the force's point (the driving point) give the
mass-normalised mode shapes: ``r_qk = phi_qk^2`` there, and
``phi_pk = r_pk / phi_qk`` at every other sensor.
"""
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..physics.structure import SENSOR_KINDS, Structure
from ..statespace.subspace import fd_subspace
from ..utils.validation import as_signal_list, check_period
from .readings import measured_frf

__all__ = ["ModalFit", "fit_modes", "modal_nominal", "subspace_poles"]

#: How far outside the fitted band a mode may sit (factors of its edges).
BAND_MARGIN = (0.8, 1.25)
#: Evaluations of the poles' least squares (a fit that needs more is
#: asking for modes the data do not hold).
MAX_NFEV = 200
#: Most modes ``n_modes="auto"`` tries, and the counts in a row that may
#: fail before it stops (a distorted resonance can fail one count and not
#: the next).
MAX_AUTO_MODES, AUTO_MISSES = 15, 3
#: A count is taken only where it explains this share of the misfit the
#: last count taken left: noise and distortion give spare modes that pass
#: every other test (a chain's three modes with 2 % noise became five).
AUTO_MIN_GAIN = 0.1
#: The residual modes sit this factor below and above the band's edges, with
#: this damping ratio: a mode far outside the band adds a stiffness-like
#: (above) or mass-like (below) term, which a well-damped mode there
#: reproduces inside the band and a structure can simulate.
RESIDUAL_FACTOR, RESIDUAL_DAMPING = 4.0, 0.3
#: Damping ratios a mode may have.
MIN_DAMPING, MAX_DAMPING = 1e-4, 0.3


@dataclass(frozen=True)
class ModalFit:
    """Modes fitted to a frequency response from one force.

    Attributes
    ----------
    frequencies : ndarray of shape (n_modes,)
        Natural frequencies, Hz, ascending.
    damping_ratios : ndarray of shape (n_modes,)
    residues : ndarray of shape (n_outputs, n_modes)
        ``r_pk``: mode ``k``'s term at output ``p`` is
        ``r_pk (i w)^v / (w_k^2 - w^2 + 2 i zeta_k w_k w)``, ``v`` the
        sensor's derivative order.
    residual_frequencies, residual_damping_ratios : ndarray of shape (2,)
        The residual modes, one below the band and one above it
        (``RESIDUAL_FACTOR`` from its edges), which stand for the modes
        outside it.
    residual_residues : ndarray of shape (n_outputs, 2)
    relative_error : float
        Rms misfit of the FRF over its rms, all outputs.
    """

    frequencies: np.ndarray
    damping_ratios: np.ndarray
    residues: np.ndarray
    residual_frequencies: np.ndarray
    residual_damping_ratios: np.ndarray
    residual_residues: np.ndarray
    relative_error: float


def _residual_poles(w):
    """The two residual modes' ``(omega, zeta)``: one above the band and one
    below it, standing for the modes outside it."""
    return (np.array([w.min() / RESIDUAL_FACTOR, w.max() * RESIDUAL_FACTOR]),
            np.full(2, RESIDUAL_DAMPING))


def _basis(w, omega, zeta, order):
    """Columns of the modal model at ``w`` (rad/s): one per mode, the
    residual modes last."""
    lo_hi, damping = _residual_poles(w)
    omega, zeta = np.r_[omega, lo_hi], np.r_[zeta, damping]
    return (1j * w[:, None]) ** order / (omega**2 - w[:, None] ** 2 + 2j * zeta * omega * w[:, None])


def _residues(w, G, omega, zeta, order):
    """Real residues of every output for the poles ``(omega, zeta)`` and
    the residual modes, by linear least squares, and the misfit."""
    B = _basis(w, omega, zeta, order)
    A = np.vstack([B.real, B.imag])
    rhs = np.vstack([G.real, G.imag])
    coef = np.linalg.lstsq(A, rhs, rcond=None)[0]
    return coef, A @ coef - rhs


def fit_modes(freqs, frf, n_modes, *, fs, kind="acceleration"):
    """Modes of a frequency response from one force.

    Parameters
    ----------
    freqs : array-like of shape (n_lines,)
        Frequencies, Hz (> 0).
    frf : array-like of shape (n_lines, n_outputs), complex
        Response per unit force at each output.
    n_modes : int
        Modes in the band.
    fs : float
        Sampling rate of the data, Hz (the subspace start works in ``z``).
    kind : {"displacement", "velocity", "acceleration"}, default="acceleration"
        What the outputs measure.

    Returns
    -------
    ModalFit

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.gap.modal_nominal import fit_modes
    >>> from sklearn_pnlss.physics import Structure
    >>> s = Structure.from_modes([5.0, 12.0], [0.02, 0.01], [[0.5, 0.4], [0.6, -0.3]],
    ...                          points=["wing", "payload"])
    >>> f = np.linspace(1.0, 20.0, 400)
    >>> H = s.frequency_response(f, inputs=["wing"],
    ...                          sensors=[("wing", "acceleration"), ("payload", "acceleration")])
    >>> fit = fit_modes(f, H[:, :, 0], 2, fs=100.0)
    >>> np.round(fit.frequencies, 6), np.round(fit.damping_ratios, 6)
    (array([ 5., 12.]), array([0.02, 0.01]))
    """
    w = 2 * np.pi * np.asarray(freqs, dtype=np.float64)
    G = np.asarray(frf, dtype=complex)
    G = G[:, None] if G.ndim == 1 else G
    if w.ndim != 1 or G.shape[0] != w.size or np.any(w <= 0) or not np.all(np.isfinite(G)):
        raise ValueError(f"freqs must be positive and frf finite with one row per frequency, got shapes "
                         f"{np.shape(freqs)} and {np.shape(frf)}.")
    if kind not in SENSOR_KINDS:
        raise ValueError(f"kind must be one of {SENSOR_KINDS}, got {kind!r}.")
    order = SENSOR_KINDS.index(kind)
    n_modes = int(n_modes)
    if w.size < 2 * n_modes + 2:
        raise ValueError(f"{w.size} lines are too few for {n_modes} modes: give more lines or fewer modes.")
    omega, zeta = _start(w, G, n_modes, fs)
    scale = np.sqrt(np.mean(np.abs(G) ** 2, axis=0))  # each output weighs the same

    def misfit(theta):
        om, ze = np.exp(theta[:n_modes]), np.exp(theta[n_modes:])
        return (_residues(w, G / scale, om, ze, order)[1]).ravel()

    # the modes stay in the band (a pole that leaves it fits the edge of the
    # band, not a mode) and stay modes (a damping ratio above MAX_DAMPING
    # is a trend, not a resonance)
    lower = np.log(np.r_[np.full(n_modes, BAND_MARGIN[0] * w.min()), np.full(n_modes, MIN_DAMPING)])
    upper = np.log(np.r_[np.full(n_modes, BAND_MARGIN[1] * w.max()), np.full(n_modes, MAX_DAMPING)])
    start = np.clip(np.log(np.r_[omega, zeta]), lower + 1e-9, upper - 1e-9)
    theta = least_squares(misfit, start, bounds=(lower, upper), method="trf", xtol=1e-12, ftol=1e-12,
                          max_nfev=MAX_NFEV).x
    omega, zeta = np.exp(theta[:n_modes]), np.exp(theta[n_modes:])
    rank = np.argsort(omega)
    omega, zeta = omega[rank], zeta[rank]
    coef, residual = _residues(w, G, omega, zeta, order)
    error = float(np.sqrt(np.sum(residual**2) / np.sum(np.abs(G) ** 2)))
    lo_hi, damping = _residual_poles(w)
    return ModalFit(omega / (2 * np.pi), zeta, coef[:n_modes].T, lo_hi / (2 * np.pi), damping, coef[n_modes:].T,
                    error)


def subspace_poles(w, G, order, fs):
    """The continuous-time poles (rad/s) of a frequency-domain subspace
    model of order ``order`` of an FRF ``G`` (n_freqs, n_outputs) at the
    frequencies ``w`` (rad/s) of data sampled at ``fs``."""
    A = fd_subspace(G[:, :, None], np.exp(1j * w / fs), int(order), estimate_d=True)[0]
    return np.log(np.linalg.eigvals(A).astype(complex)) * fs


def _start(w, G, n_modes, fs):
    """Starting poles: the ``n_modes`` least damped oscillating poles of a
    subspace model of the FRF (order twice the modes) inside the band."""
    found = []
    for extra in (0, 2, 4):
        s = subspace_poles(w, G, 2 * n_modes + extra, fs)
        s = s[(s.imag > 0) & (s.imag >= w.min() * 0.9) & (s.imag <= w.max() * 1.1)]
        if s.size >= n_modes:
            found = s[np.argsort(-s.real / np.abs(s))[:n_modes]]
            break
    if len(found) < n_modes:
        raise ValueError(f"the FRF does not show {n_modes} modes in its band: ask for fewer modes or widen the band.")
    return np.abs(found), -found.real / np.abs(found)


def _unresolved(fit, drive, driving_point, band):
    """Why a fit's modes are not a structure's (None when they are): a mode
    outside the fitted band (it fits the band's edge, the residual modes'
    work), two modes closer than their half-power bandwidths together (the
    data tell them from one distorted resonance by their residues alone,
    which then grow large and opposite), or a residue at the driving point
    that is not positive (a mode the force does not reach, or no mode)."""
    f, half = fit.frequencies, fit.frequencies * fit.damping_ratios
    outside = f[(f < band[0]) | (f > band[1])]
    if outside.size:
        return f"the modes at {np.round(outside, 3)} Hz lie outside the band {np.round(band, 3)} Hz"
    close = np.flatnonzero(np.diff(f) < half[:-1] + half[1:])
    if close.size:
        k = close[0]
        return f"the modes at {f[k]:.3f} and {f[k + 1]:.3f} Hz lie within their bandwidths of each other"
    bad = np.flatnonzero(fit.residues[drive] <= 0)
    if bad.size:
        return (f"the modes at {np.round(f[bad], 3)} Hz have a residue of the wrong sign at the driving point "
                f"{driving_point!r}: they cannot be mass-normalised")
    return None


def modal_nominal(X, y, *, fs, points, driving_point, n_modes="auto", kind="acceleration", period=None,
                  f_band=None, residual_modes=True):
    """The linear structure whose modes fit the measured frequency response.

    Parameters
    ----------
    X : signals, one force each
        Measured force (one input).
    y : signals, one column per sensor
        Measured responses at ``points``.
    fs : float
        Sampling rate, Hz.
    points : sequence of str
        The sensors' points, one per column of ``y``.
    driving_point : str
        The point among ``points`` where the force acts: its sensor's
        residues mass-normalise the mode shapes.
    n_modes : int or "auto", default="auto"
        Modes in the band; "auto": the most the data tell apart, counted up
        to ``MAX_AUTO_MODES`` while one of the next ``AUTO_MISSES`` counts
        gives modes that are a structure's (inside the band, apart by more
        than their bandwidths, each with a positive residue at the driving
        point) and explains ``AUTO_MIN_GAIN`` of the misfit left.
    kind : {"displacement", "velocity", "acceleration"}, default="acceleration"
    period : int, default=None
        Samples per period when every signal is a whole number of
        steady-state periods.
    f_band : (float, float), default=None
        Band of the fit, Hz; None: every excited line.
    residual_modes : bool, default=True
        Keep the fit's residual modes (below and above the band, standing
        for the modes outside it) in the structure, where the driving point
        sees them with the right sign: a driving point's acceleration owes
        much to the modes above the band.

    Returns
    -------
    structure : Structure
        ``Structure.from_modes`` of the fitted modes at ``points``; the fit
        itself is its attribute ``modal_fit_``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.gap.modal_nominal import modal_nominal
    >>> from sklearn_pnlss.physics import Structure
    >>> truth = Structure.from_modes([5.0, 12.0], [0.02, 0.01], [[0.5, 0.4], [0.6, -0.3]],
    ...                              points=["wing", "payload"])
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(4096)
    >>> sensors = [("wing", "acceleration"), ("payload", "acceleration")]
    >>> a = truth.simulate(u, fs=100.0, inputs="wing", sensors=sensors, periodic=True,
    ...                    oversampling=20, decimation=(2, 2, 5))
    >>> s = modal_nominal(np.tile(u, 2), np.tile(a, (2, 1)), fs=100.0, points=["wing", "payload"],
    ...                   driving_point="wing", n_modes=2, period=4096, f_band=(1.0, 30.0))
    >>> np.round(s.modal_fit_.frequencies, 2), np.round(s.point_matrix[:, :2], 2)
    (array([ 5., 12.]), array([[ 0.5,  0.4],
           [ 0.6, -0.3]]))
    """
    period = check_period(period)
    u_list = [s[:, 0] for s in as_signal_list(X, name="X", min_samples=16)[0]]
    y_list = as_signal_list(y, name="y", min_samples=16)[0]
    points = [str(p) for p in points]
    if len(u_list) != len(y_list) or any(u.size != v.shape[0] for u, v in zip(u_list, y_list)):
        raise ValueError("X and y must hold the same number of signals of the same lengths.")
    if any(v.shape[1] != len(points) for v in y_list):
        raise ValueError(f"y must have one column per point ({len(points)}), got {y_list[0].shape[1]}.")
    if driving_point not in points:
        raise ValueError(f"driving_point must be one of the sensors' points {points}, got {driving_point!r}.")
    lines, G, n = measured_frf(u_list, y_list, period)
    freqs = lines * fs / n
    if f_band is not None:
        keep = (freqs >= f_band[0]) & (freqs <= f_band[1])
        freqs, G = freqs[keep], G[keep]
    drive = points.index(driving_point)
    band = (freqs.min(), freqs.max())
    if n_modes == "auto":
        # the most modes the data tell apart: counts up while a fit of one
        # or two modes more can still be a structure's
        fit, misses = None, 0
        for count in range(1, MAX_AUTO_MODES + 1):
            if freqs.size < 2 * count + 2 or misses == AUTO_MISSES:
                break
            try:
                trial = fit_modes(freqs, G, count, fs=fs, kind=kind)
            except ValueError:
                trial = None
            if (trial is None or _unresolved(trial, drive, driving_point, band) is not None
                    or (fit is not None and trial.relative_error > (1 - AUTO_MIN_GAIN) * fit.relative_error)):
                misses += 1
                continue
            fit, misses = trial, 0
        if fit is None:
            raise ValueError("no mode could be fitted and mass-normalised: check the band (f_band) and the "
                             "driving point's sensor.")
    else:
        if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
            raise ValueError(f"n_modes must be a positive int or 'auto', got {n_modes!r}.")
        fit = fit_modes(freqs, G, n_modes, fs=fs, kind=kind)
        reason = _unresolved(fit, drive, driving_point, band)
        if reason is not None:
            raise ValueError(f"{reason}: ask for fewer modes (or n_modes='auto') or narrow f_band.")
    shapes = fit.residues / np.sqrt(fit.residues[drive])
    freqs_all, zeta_all, coupled = fit.frequencies, fit.damping_ratios, np.ones(fit.frequencies.size, bool)
    if residual_modes:
        # the residual modes the driving point sees with the right sign
        ok = fit.residual_residues[drive] > 0
        shapes = np.hstack([shapes, fit.residual_residues[:, ok] / np.sqrt(fit.residual_residues[drive, ok])])
        freqs_all = np.r_[freqs_all, fit.residual_frequencies[ok]]
        zeta_all = np.r_[zeta_all, fit.residual_damping_ratios[ok]]
        # seen from the driving point only: no connection acts on them
        coupled = np.r_[coupled, np.zeros(int(np.sum(ok)), bool)]
    structure = Structure.from_modes(freqs_all, zeta_all, shapes, points=points, coupled=coupled)
    structure.modal_fit_ = fit
    return structure
