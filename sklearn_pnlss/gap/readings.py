"""Readings of measured signals by themselves, shared by the candidates'
clues, the where-analysis, the verdict and the nominals read off data:
derivatives of a displacement, the input's frequency content, the measured
frequency response, the force the nominal leaves unbalanced along the
measured motion, and the misfit of a simulation."""
import numpy as np

from ..frequency.bla import welch_bla
from ..utils.validation import is_periodic

__all__ = ["signal_derivative", "content_limit", "measured_frf", "missing_force", "periods_of", "misfit"]

#: Segment length of the Welch estimate of data without a period.
WELCH_SEGMENT = 4096


def measured_frf(u_list, y_list, period):
    """The frequency response from one force to every output of the data.

    Steady-state periodic signals (each a whole number of ``period``
    samples): the period-averaged spectra, pooled over the signals (H1);
    otherwise Welch's H1 in segments of ``WELCH_SEGMENT`` samples (fewer
    for short records).

    Parameters
    ----------
    u_list : list of ndarray (n_samples_i,)
    y_list : list of ndarray (n_samples_i, n_outputs)
    period : int or None

    Returns
    -------
    lines : ndarray of int
        Excited DFT lines (cycles per record of ``n`` samples).
    frf : ndarray (n_lines, n_outputs), complex
    n : int
        Samples per record the lines count in.
    """
    if period is not None and all(is_periodic(u.size, period) for u in u_list):
        U = np.array([np.fft.rfft(u.reshape(-1, period).mean(0)) for u in u_list])
        Y = np.array([np.fft.rfft(y.reshape(-1, period, y.shape[1]).mean(0), axis=0) for y in y_list])
        power = np.sum(np.abs(U) ** 2, axis=0)
        lines = np.flatnonzero(power > 1e-6 * power.max())
        lines = lines[lines > 0]
        frf = np.sum(Y[:, lines] * U[:, lines, None].conj(), axis=0) / power[lines, None]
        return lines, frf, period
    n = min(WELCH_SEGMENT, 2 ** int(np.log2(min(u.size for u in u_list))))
    lines, frf, _ = welch_bla([u[:, None] for u in u_list], y_list, n)
    return lines, frf[:, :, 0], n


def _band_limit(n, fs, f_max):
    """DFT bins of an n-sample record kept by a low-pass at f_max."""
    f = np.fft.rfftfreq(n, 1 / fs)
    return f <= f_max


def signal_derivative(y, fs, n_periods, period, order=1, f_max=None):
    """Time derivative of a sampled displacement by the DFT.

    A periodic record (``n_periods > 0``) is differentiated exactly; any
    other record is extended by its mirror image first so that its ends do
    not ring.  Bins above ``f_max`` (default: Nyquist) are dropped, which
    keeps the noise's high-frequency part from dominating accelerations.
    """
    y = np.asarray(y, float)
    n = y.size
    if n_periods:
        ext = y
    else:
        ext = np.concatenate([y, y[::-1]])
    spec = np.fft.rfft(ext)
    w = 2 * np.pi * np.fft.rfftfreq(ext.size, 1 / fs)
    spec = spec * (1j * w) ** order
    if f_max is not None:
        spec[~_band_limit(ext.size, fs, f_max)] = 0
    if ext.size % 2 == 0:
        spec[-1] = 0  # the Nyquist bin has no defined derivative
    return np.fft.irfft(spec, ext.size)[:n]


def content_limit(u_list, fs):
    """Highest frequency worth differentiating: three times the input band
    (harmonics of a nonlinearity) capped at 80 % of Nyquist."""
    f_in = 0.0
    for u in u_list:
        p = np.abs(np.fft.rfft(u - u.mean())) ** 2
        cum = np.cumsum(p) / max(p.sum(), 1e-300)
        f_in = max(f_in, np.fft.rfftfreq(u.size, 1 / fs)[np.searchsorted(cum, 0.999)])
    return min(3 * f_in, 0.4 * fs)


def periods_of(x, P, period):
    return x[: P * period].reshape(P, period)


def missing_force(nominal, u_list, y_list, n_periods, period, fs, f_max):
    """The force the nominal equation of motion leaves unbalanced along the
    measured motion: ``u - m ydd - c yd - k y - F(y, yd)``.

    The derivatives of the measured displacement are taken by the DFT,
    band-limited to ``f_max``; periodic signals are averaged over their
    periods first (the noise drops by their number), the ends of the others
    are trimmed (they ring).  Stateful nominal elements are left out: their
    states are not measured.

    Returns
    -------
    y, yd, ydd, force : ndarray
        Displacement, velocity, acceleration and missing force, all signals
        concatenated.
    """
    ys, vs, acc, fm = [], [], [], []
    for u, y, P in zip(u_list, y_list, n_periods):
        if P:
            u, y = periods_of(u, P, period).mean(0), periods_of(y, P, period).mean(0)
        v = signal_derivative(y, fs, P, period, 1, f_max)
        a = signal_derivative(y, fs, P, period, 2, f_max)
        yf = signal_derivative(y, fs, P, period, 0, f_max)
        trim = slice(None) if P else slice(y.size // 50, y.size - y.size // 50)
        fm.append((u - nominal.mass * a - nominal.restoring_force(yf, v))[trim])
        ys.append(yf[trim])
        vs.append(v[trim])
        acc.append(a[trim])
    return tuple(map(np.concatenate, (ys, vs, acc, fm)))



def misfit(y_sim, y_meas, offsets=False):
    """Simulation minus measurement of one signal; with ``offsets``, less
    its mean: the best constant sensor offset of that record is then
    granted to every model alike (a displacement sensor's zero is rarely
    known, and a constant says nothing about the structure)."""
    r = np.asarray(y_sim) - np.asarray(y_meas)
    return r - r.mean() if offsets else r
