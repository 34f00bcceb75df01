"""Output noise level per DFT bin from steady-state periodic measurements."""
import numpy as np
from scipy.ndimage import uniform_filter1d

from ..utils.validation import is_periodic

__all__ = ["periodic_noise_variance", "signal_noise_variances"]

# Real degrees of freedom each bin's estimate of one signal's noise
# variance is smoothed to (over neighbouring bins): a weight is the inverse
# of the estimate, and one from two periods alone (2 degrees of freedom) is
# infinite in expectation.
SIGNAL_NOISE_DOF = 64


def periodic_noise_variance(y_list, period, trend_degree=0):
    """Noise variance of one period's unitary DFT (``rfft / sqrt(period)``)
    at every bin, from the spread over the periods of each signal.

    The system's steady-state response repeats every period, so what changes
    from one period to the next is noise. Signals with at least two periods
    are pooled, each with ``P - 1`` degrees of freedom.

    Parameters
    ----------
    y_list : list of ndarray (n_samples_i, p)
    period : int
    trend_degree : int, default=0
        Degree of a polynomial in the period index removed from each bin
        first (capped at ``P - 2``), so that a slow drift of the structure
        is not taken as noise; each signal then has ``P - 1 - degree``
        degrees of freedom.

    Returns
    -------
    var : ndarray of shape (period // 2 + 1, p), or None when no signal has
        two periods or more.
    """
    total, dof = 0.0, 0
    for Y in y_list:
        if not is_periodic(Y.shape[0], period) or Y.shape[0] < 2 * period:
            continue
        P = Y.shape[0] // period
        Yf = np.fft.rfft(Y.reshape(P, period, -1), axis=1) / np.sqrt(period)
        degree = min(trend_degree, P - 2)
        if degree == 0:
            residual = Yf - Yf.mean(axis=0)
        else:
            trend, _ = np.linalg.qr(np.vander(np.arange(P) - (P - 1) / 2, degree + 1, increasing=True))
            residual = Yf - np.einsum("pq,qk...->pk...", trend, np.einsum("pq,pk...->qk...", trend, Yf))
        total = total + np.sum(np.abs(residual) ** 2, axis=0)
        dof += P - 1 - degree
    return None if dof == 0 else total / dof


def signal_noise_variances(y_list, period, min_dof=SIGNAL_NOISE_DOF):
    """Each signal's own noise variance per bin of one period's unitary
    DFT, from the spread over its own periods, smoothed over neighbouring
    bins to ``min_dof`` real degrees of freedom.

    The records of a test campaign at several levels have noise of their
    own (on a structure with a joint that knocks, the knocks that do not
    repeat grow with the level): pooled, the loudest level's noise would
    weigh the quiet ones. A signal with fewer than two periods gets the
    variance pooled over the others (:func:`periodic_noise_variance`).

    Parameters
    ----------
    y_list : list of ndarray (n_samples_i, p)
    period : int
    min_dof : int, default=SIGNAL_NOISE_DOF
        A signal of ``P`` periods has ``2 (P - 1)`` real degrees of freedom
        per bin; the estimate is averaged over ``ceil(min_dof / (2 (P - 1)))``
        neighbouring bins.

    Returns
    -------
    list of ndarray of shape (period // 2 + 1, p), or None when no signal has
        two periods or more.
    """
    out = []
    for Y in y_list:
        own = periodic_noise_variance([Y], period)
        if own is not None:
            width = -(-min_dof // (2 * (Y.shape[0] // period - 1)))
            own = uniform_filter1d(own, size=width, axis=0, mode="nearest") if width > 1 else own
        out.append(own)
    if all(v is None for v in out):
        return None
    if any(v is None for v in out):  # only then are the periods of every signal read again
        pooled = periodic_noise_variance(y_list, period)
        out = [pooled if v is None else v for v in out]
    return out
