"""Excitation signals: random-phase multisines and swept sines."""
from numbers import Integral, Real

import numpy as np
from scipy import fft as sp_fft
from sklearn.utils import check_random_state

__all__ = ["multisine", "multisine_lines", "swept_sine", "linear_chirp", "bouc_wen_sweep"]

_KINDS = ("full", "odd", "random_odd")


def _check_int(name, value, minimum):
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}.")
    return int(value)


def _check_real(name, value, *, positive=True):
    if isinstance(value, bool) or not isinstance(value, Real) or not np.isfinite(value):
        raise ValueError(f"{name} must be a finite real number, got {value!r}.")
    if positive and value <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}.")
    return float(value)


def multisine_lines(n_samples, *, fs, f_band, kind="full", group_size=3, random_state=None):
    """DFT bins excited by a multisine.

    Parameters
    ----------
    n_samples : int
        Samples per period ``N``; bin ``k`` is at ``k * fs / N``.
    fs : float
        Sampling rate, Hz.
    f_band : tuple of float
        ``(f_min, f_max)`` in Hz, inside ``(0, fs / 2]``; bins with
        ``f_min <= k fs / N <= f_max`` (``k >= 1``) are candidates.
    kind : {"full", "odd", "random_odd"}, default="full"
        All candidate bins, the odd ones, or the odd ones minus one randomly
        chosen bin in every group of ``group_size`` consecutive odd bins (a
        trailing incomplete group keeps all its bins).
    group_size : int, default=3
        Group length for ``"random_odd"`` (>= 2).
    random_state : int, RandomState instance or None, default=None
        Seed of the ``"random_odd"`` choice.

    Returns
    -------
    lines : ndarray of int
        Excited bin indices, increasing.

    Examples
    --------
    >>> from sklearn_pnlss.signals import multisine_lines
    >>> multisine_lines(16, fs=16.0, f_band=(1.0, 7.0), kind="odd")
    array([1, 3, 5, 7])
    """
    n_samples = _check_int("n_samples", n_samples, 2)
    fs = _check_real("fs", fs)
    try:
        f_min, f_max = (float(f) for f in f_band)
    except (TypeError, ValueError):
        raise ValueError(f"f_band must be a pair (f_min, f_max), got {f_band!r}.")
    if not (0.0 < f_min <= f_max <= fs / 2):
        raise ValueError(
            f"f_band must satisfy 0 < f_min <= f_max <= fs/2 = {fs / 2:g}, got {f_band!r}."
        )
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}.")
    group_size = _check_int("group_size", group_size, 2)

    # Small tolerance so that a band edge given as k * fs / N includes bin k.
    eps = 1e-9
    k_min = max(1, int(np.ceil(f_min * n_samples / fs - eps)))
    k_max = min(n_samples // 2, int(np.floor(f_max * n_samples / fs + eps)))
    lines = np.arange(k_min, k_max + 1)
    if kind != "full":
        lines = lines[lines % 2 == 1]
    if kind == "random_odd":
        rng = check_random_state(random_state)
        keep = np.ones(lines.size, dtype=bool)
        for start in range(0, lines.size - group_size + 1, group_size):
            keep[start + rng.randint(group_size)] = False
        lines = lines[keep]
    if lines.size == 0:
        raise ValueError(
            f"no {kind!r} DFT line lies in f_band={f_band!r} for n_samples={n_samples} "
            f"and fs={fs:g} (line spacing {fs / n_samples:g} Hz)."
        )
    return lines


def multisine(n_samples=8192, *, fs=750.0, f_band=(5.0, 150.0), rms=1.0, kind="full",
              n_periods=1, n_realizations=1, n_inputs=1, group_size=3, random_state=None):
    """Random-phase multisine with a flat amplitude spectrum.

    Every realisation and every input gets independent phases, uniform in
    ``[0, 2 pi)``, on the same excited lines; the period is the inverse real
    FFT, scaled to exactly ``rms`` and repeated ``n_periods`` times.

    Parameters
    ----------
    n_samples : int, default=8192
        Samples per period.
    fs : float, default=750.0
        Sampling rate, Hz.
    f_band : tuple of float, default=(5.0, 150.0)
        Excited band ``(f_min, f_max)`` in Hz, inside ``(0, fs / 2]``.
    rms : float, default=1.0
        Rms of each realisation and input.
    kind : {"full", "odd", "random_odd"}, default="full"
        Line selection, see :func:`multisine_lines`.  For ``"random_odd"``
        the detection lines are drawn once and shared by all realisations.
    n_periods : int, default=1
        Number of repeated periods.
    n_realizations : int, default=1
        Number of independent phase realisations.
    n_inputs : int, default=1
        Number of inputs (independent phases per input).
    group_size : int, default=3
        Group length for ``"random_odd"``.
    random_state : int, RandomState instance or None, default=None
        Seed of the phases (and of the random-odd line choice).

    Returns
    -------
    X : ndarray of shape (n_realizations, n_periods * n_samples, n_inputs)
        The multisines.
    lines : ndarray of int
        Excited DFT bins ``k`` (frequency ``k * fs / n_samples``).

    Examples
    --------
    >>> from sklearn_pnlss.signals import multisine
    >>> X, lines = multisine(1024, fs=750.0, f_band=(5.0, 150.0), rms=50.0,
    ...                      n_periods=2, n_realizations=3, random_state=0)
    >>> X.shape
    (3, 2048, 1)
    >>> round(float(X[0, :, 0].std()), 9)
    50.0
    """
    n_samples = _check_int("n_samples", n_samples, 2)
    rms = _check_real("rms", rms)
    n_periods = _check_int("n_periods", n_periods, 1)
    n_realizations = _check_int("n_realizations", n_realizations, 1)
    n_inputs = _check_int("n_inputs", n_inputs, 1)
    rng = check_random_state(random_state)
    lines = multisine_lines(n_samples, fs=fs, f_band=f_band, kind=kind,
                            group_size=group_size, random_state=rng)

    phases = rng.uniform(0.0, 2.0 * np.pi, size=(n_realizations, n_inputs, lines.size))
    spec = np.zeros((n_realizations, n_inputs, n_samples // 2 + 1), dtype=complex)
    spec[..., lines] = np.exp(1j * phases)
    if n_samples % 2 == 0 and lines[-1] == n_samples // 2:
        # A real signal has a real Nyquist bin; keep its amplitude flat with
        # a random sign (irfft halves the weight of this bin, hence the 2).
        spec[..., -1] = np.where(np.cos(phases[..., -1]) >= 0.0, 2.0, -2.0)
    x = sp_fft.irfft(spec, n_samples, axis=-1)
    x *= rms / np.sqrt(np.mean(x**2, axis=-1, keepdims=True))
    x = np.tile(x, (1, 1, n_periods))
    return np.ascontiguousarray(np.transpose(x, (0, 2, 1))), lines


def linear_chirp(t, *, f_start, rate, amplitude=1.0, phase=0.0):
    """Linear chirp ``amplitude * sin(2 pi (f_start t + rate t^2 / 2) + phase)``.

    Evaluates the swept sine at any time vector, e.g. at the integration
    rate of a simulator.

    Parameters
    ----------
    t : array-like
        Times, s.
    f_start : float
        Instantaneous frequency at ``t = 0``, Hz.
    rate : float
        Sweep rate, Hz/s (instantaneous frequency ``f_start + rate t``).
    amplitude : float, default=1.0
        Amplitude.
    phase : float, default=0.0
        Phase at ``t = 0``, rad.

    Returns
    -------
    u : ndarray
        Same shape as ``t``.

    Examples
    --------
    >>> from sklearn_pnlss.signals import linear_chirp
    >>> float(linear_chirp(0.0, f_start=18.0, rate=1 / 6, amplitude=40.0))
    0.0
    """
    t = np.asarray(t, dtype=np.float64)
    return amplitude * np.sin(2.0 * np.pi * (f_start * t + 0.5 * rate * t * t) + phase)


def swept_sine(n_samples, *, fs, f_start, f_stop, amplitude=1.0, phase=0.0, oversampling=1):
    """Linear swept sine from ``f_start`` to ``f_stop`` over ``n_samples / fs`` s.

    Parameters
    ----------
    n_samples : int
        Number of samples at rate ``fs``; the duration ``T = n_samples / fs``
        sets the sweep rate ``(f_stop - f_start) / T``.
    fs : float
        Sampling rate, Hz.
    f_start, f_stop : float
        Start and stop frequencies, Hz (``f_stop < f_start`` sweeps down).
    amplitude : float, default=1.0
        Amplitude.
    phase : float, default=0.0
        Phase at ``t = 0``, rad.
    oversampling : int, default=1
        Evaluate the same sweep at ``oversampling * fs`` instead
        (``n_samples * oversampling`` samples), e.g. for a simulator's
        integration grid.

    Returns
    -------
    u : ndarray of shape (n_samples * oversampling,)

    Examples
    --------
    >>> from sklearn_pnlss.signals import swept_sine
    >>> swept_sine(1500, fs=750.0, f_start=10.0, f_stop=20.0).shape
    (1500,)
    """
    n_samples = _check_int("n_samples", n_samples, 1)
    fs = _check_real("fs", fs)
    f_start = _check_real("f_start", f_start, positive=False)
    f_stop = _check_real("f_stop", f_stop, positive=False)
    amplitude = _check_real("amplitude", amplitude, positive=False)
    oversampling = _check_int("oversampling", oversampling, 1)
    rate = (f_stop - f_start) * fs / n_samples
    t = np.arange(n_samples * oversampling) / (fs * oversampling)
    return linear_chirp(t, f_start=f_start, rate=rate, amplitude=amplitude, phase=phase)


def bouc_wen_sweep(n_samples=153000, fs=750.0, amplitude=40.0, *, oversampling=1):
    """The Bouc-Wen benchmark's test sweep, ``40 sin(2 pi (18 t + t^2 / 12))``.

    A linear chirp from 18 Hz at 10 Hz/min (52 Hz after the default
    204 s).  The sweep rate stays 1/6 Hz/s whatever ``n_samples``.

    Parameters
    ----------
    n_samples : int, default=153000
        Number of samples at rate ``fs``.
    fs : float, default=750.0
        Sampling rate, Hz.
    amplitude : float, default=40.0
        Amplitude, N.
    oversampling : int, default=1
        Evaluate at ``oversampling * fs`` (exact input for a simulator).

    Returns
    -------
    u : ndarray of shape (n_samples * oversampling,)

    Examples
    --------
    >>> from sklearn_pnlss.signals import bouc_wen_sweep
    >>> u = bouc_wen_sweep()
    >>> u.shape, float(abs(u).max()) <= 40.0
    ((153000,), True)
    """
    n_samples = _check_int("n_samples", n_samples, 1)
    fs = _check_real("fs", fs)
    amplitude = _check_real("amplitude", amplitude, positive=False)
    oversampling = _check_int("oversampling", oversampling, 1)
    t = np.arange(n_samples * oversampling) / (fs * oversampling)
    return linear_chirp(t, f_start=18.0, rate=1.0 / 6.0, amplitude=amplitude)
