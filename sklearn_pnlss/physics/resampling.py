"""Resampling as the Bouc-Wen benchmark data were produced.

* :func:`decimate_fir` reproduces MATLAB's ``decimate(x, r, 'fir')``
  (30th-order Hamming FIR, point-reflected ends, zero-phase picks), or its
  circular counterpart for a periodic steady-state record.
* :func:`upsample_fft` interpolates by FFT zero padding: exact for a periodic
  band-limited record, and accurate for a non-periodic smooth record after a
  point-reflected extension.
"""
from functools import lru_cache
from numbers import Integral

import numpy as np
from scipy import fft as sp_fft
from scipy.signal import firwin

__all__ = ["fir_decimation_filter", "decimate_fir", "upsample_fft"]

_FIR_ORDER = 30  # MATLAB decimate's 'fir' option uses a 30th-order filter
_HALF = _FIR_ORDER // 2


def _check_factor(name, r):
    if isinstance(r, bool) or not isinstance(r, Integral) or r < 1:
        raise ValueError(f"{name} must be a positive integer, got {r!r}.")
    return int(r)


def check_factors(factors, name="factors"):
    """Decimation factors as a non-empty tuple of positive ints (one int is
    one stage)."""
    if isinstance(factors, Integral) and not isinstance(factors, bool):
        factors = (factors,)
    try:
        factors = tuple(factors)
    except TypeError:
        raise ValueError(f"{name} must be an int or a sequence of ints, got {factors!r}.") from None
    if not factors:
        raise ValueError(f"{name} must contain at least one decimation factor.")
    return tuple(_check_factor(f"each factor of {name}", r) for r in factors)


def check_signal(x, name="x"):
    """A 1-D finite float64 record, or a ValueError naming ``name``."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got an array of shape {x.shape}.")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} contains NaN or infinite values.")
    return x


def fir_decimation_filter(r):
    """Coefficients of MATLAB's ``fir1(30, 1/r)`` (Hamming, unit DC gain).

    Parameters
    ----------
    r : int
        Decimation factor (>= 2).

    Returns
    -------
    b : ndarray of shape (31,)

    Examples
    --------
    >>> from sklearn_pnlss.physics import fir_decimation_filter
    >>> round(float(fir_decimation_filter(2).sum()), 12)
    1.0
    """
    r = _check_factor("r", r)
    if r < 2:
        raise ValueError(f"r must be >= 2 for a decimation filter, got {r}.")
    return firwin(_FIR_ORDER + 1, 1.0 / r, window="hamming")


@lru_cache(maxsize=None)
def _reversed_filter(r):
    """``fir_decimation_filter(r)`` reversed (a correlation kernel), computed once."""
    b = fir_decimation_filter(r)[::-1].copy()
    b.flags.writeable = False
    return b


def _decimate_once(x, r, periodic):
    """One decimation stage of a record, or of each column of a 2-D array
    of records (axis 0 is time)."""
    n = x.shape[0]
    if periodic:
        if n % r:
            raise ValueError(
                f"a periodic record must have a length divisible by the decimation "
                f"factor; got {n} samples for factor {r}."
            )
        if n < _HALF:
            raise ValueError(f"x is too short ({n} samples) for circular decimation.")
        ext = np.concatenate([x[-_HALF:], x, x[:_HALF]])
        first = 2 * _HALF  # filtered sample centred on x[0]
    else:
        n_back = 2 * (_FIR_ORDER + 1)
        if n <= n_back:
            raise ValueError(
                f"x must have more than {n_back} samples for FIR decimation, got {n}."
            )
        # MATLAB: 2 x(1) - x(32:-1:2) in front, 2 x(end) - x(end-1:-1:end-62) behind.
        front = 2.0 * x[0] - x[_FIR_ORDER + 1:0:-1]
        back = 2.0 * x[-1] - x[-2:-n_back - 2:-1]
        ext = np.concatenate([front, x, back])
        first = front.shape[0] + _HALF
    # MATLAB's filter(b, 1, ext) picked at first, first + r, ...: only the
    # kept samples are computed (each a window of ext times the reversed
    # filter), where filtering every sample cost r times as much.
    n_out = -(-n // r)
    start = first - _FIR_ORDER
    windows = np.lib.stride_tricks.sliding_window_view(ext, _FIR_ORDER + 1, axis=0)
    return windows[start: start + r * n_out: r][:n_out] @ _reversed_filter(r)


def decimate_columns(x, factors, *, periodic=False):
    """:func:`decimate_fir` of each column of ``x`` (n_samples, n_columns):
    the same filter on records that share their length, such as the
    sensitivities of a simulation."""
    x = np.asarray(x, dtype=np.float64)
    for r in check_factors(factors):
        if r > 1:
            x = _decimate_once(x, r, periodic)
    return x


def decimate_fir(x, factors, *, periodic=False):
    """Low-pass filter and downsample like MATLAB ``decimate(x, r, 'fir')``.

    Each stage uses ``b = fir1(30, 1/r)`` (Hamming window) and keeps output
    sample ``k`` centred on input sample ``k r`` (zero phase).  A
    non-periodic record is extended by point reflection at both ends exactly
    as MATLAB does and gives ``ceil(n / r)`` samples; a periodic record is
    filtered circularly, which equals MATLAB's interior samples of a long
    steady-state record.

    Parameters
    ----------
    x : array-like of shape (n_samples,)
        Record at the high rate.
    factors : int or sequence of int
        Decimation factor, or the chain of factors applied in turn (e.g.
        ``(2, 2, 5)`` for the benchmark multisines, ``(20,)`` for its sweep).
    periodic : bool, default=False
        Treat ``x`` as one period of a periodic signal.

    Returns
    -------
    y : ndarray of shape (ceil(n_samples / prod(factors)),)

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.physics import decimate_fir
    >>> t = np.arange(2000) / 2000.0
    >>> y = decimate_fir(np.sin(2 * np.pi * 5 * t), (2, 5), periodic=True)
    >>> y.shape
    (200,)
    """
    return decimate_columns(check_signal(x), factors, periodic=periodic)


def upsample_fft(x, factor, *, periodic):
    """Band-limited interpolation by FFT zero padding.

    Parameters
    ----------
    x : array-like of shape (n_samples,)
        Samples at the low rate.
    factor : int
        Upsampling factor.
    periodic : bool
        If True, ``x`` is one period of a periodic band-limited signal and the
        interpolation is exact (the Nyquist bin, if any, is split evenly
        between the positive and negative frequency).  If False, the record is
        first extended by point reflection (``2 x[0] - x`` reversed in front,
        ``2 x[-1] - x`` reversed behind) so that the implicit periodic
        extension is continuous with a continuous slope; for a smooth record
        the error is then tiny away from the far ends of the extension.

    Returns
    -------
    x_fine : ndarray of shape (n_samples * factor,)
        ``x_fine[i * factor] == x[i]`` up to round-off; the last ``factor - 1``
        samples lie after the last input sample.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.physics import upsample_fft
    >>> x = np.cos(2 * np.pi * 3 * np.arange(16) / 16)
    >>> xf = upsample_fft(x, 4, periodic=True)
    >>> bool(np.allclose(xf, np.cos(2 * np.pi * 3 * np.arange(64) / 64)))
    True
    """
    x = check_signal(x)
    factor = _check_factor("factor", factor)
    n = x.size
    if n < 2:
        raise ValueError(f"x must have at least 2 samples, got {n}.")
    if factor == 1:
        return x.copy()
    if periodic:
        return _upsample_periodic(x, factor)
    ext = np.concatenate([2.0 * x[0] - x[:0:-1], x, 2.0 * x[-1] - x[-2::-1]])
    # Pad to an FFT-friendly length (3n - 2 can be nearly prime, 100x slower)
    # with a straight bridge back to the first sample, which also removes
    # the jump of the implicit periodic extension, far from the record.
    n_pad = sp_fft.next_fast_len(ext.size, real=True) - ext.size
    if n_pad:
        ramp = np.arange(1, n_pad + 1) / (n_pad + 1)
        ext = np.concatenate([ext, ext[-1] + (ext[0] - ext[-1]) * ramp])
    fine = _upsample_periodic(ext, factor)
    start = (n - 1) * factor
    return fine[start: start + n * factor]


def _upsample_periodic(x, factor):
    n = x.size
    spec = sp_fft.rfft(x)
    padded = np.zeros(n * factor // 2 + 1, dtype=complex)
    padded[: spec.size] = spec
    if n % 2 == 0:
        # The low-rate Nyquist bin stands for +fs/2 and -fs/2 together.
        padded[n // 2] *= 0.5
    return sp_fft.irfft(padded, n * factor) * factor
