"""Output noise level per DFT bin from steady-state periodic measurements."""
import numpy as np

from ..utils.validation import is_periodic

__all__ = ["periodic_noise_variance"]


def periodic_noise_variance(y_list, period):
    """Noise variance of one period's unitary DFT (``rfft / sqrt(period)``)
    at every bin, from the spread over the periods of each signal.

    The system's steady-state response repeats every period, so what changes
    from one period to the next is noise. Signals with at least two periods
    are pooled, each with ``P - 1`` degrees of freedom.

    Parameters
    ----------
    y_list : list of ndarray (n_samples_i, p)
    period : int

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
        total = total + np.var(Yf, axis=0, ddof=1) * (P - 1)
        dof += P - 1
    return None if dof == 0 else total / dof
