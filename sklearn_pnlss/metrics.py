"""Error measures used across the field: rms simulation error in m and dB."""
import numpy as np

from .utils.validation import as_signal_list

__all__ = ["rms_error", "rms_db_scorer", "to_db"]


def to_db(value):
    """Amplitude in decibels, ``20 log10(value)``."""
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(value)


def rms_error(y_true, y_pred, db=False):
    """Root-mean-square simulation error over all signals, samples and outputs.

    Signals are concatenated, so a long signal weighs more than a short one,
    exactly as if they were one record.

    Parameters
    ----------
    y_true, y_pred : array-like or list of array-like
        Signals in the library convention (3-D array, list, or one signal).
    db : bool, default=False
        Return ``20 log10(rms)`` instead of the rms in the signal's units.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.metrics import rms_error
    >>> rms_error(np.zeros(4), np.full(4, 1e-3), db=True)
    -60.0
    """
    true, _ = as_signal_list(y_true, name="y_true", min_samples=1)
    pred, _ = as_signal_list(y_pred, name="y_pred", min_samples=1)
    if len(true) != len(pred) or any(
        a.shape != b.shape for a, b in zip(true, pred)
    ):
        raise ValueError(
            "y_true and y_pred must hold the same number of signals with the "
            f"same shapes; got {[a.shape for a in true]} and "
            f"{[b.shape for b in pred]}."
        )
    sq = sum(float(np.sum((a - b) ** 2)) for a, b in zip(true, pred))
    n = sum(a.size for a in true)
    value = np.sqrt(sq / n)
    return float(to_db(value)) if db else float(value)


def rms_db_scorer(estimator, X, y):
    """Scorer for ``GridSearchCV(scoring=...)``: minus the rms error in dB.

    Higher is better: a model at -90 dB scores 90.

    Examples
    --------
    >>> from sklearn_pnlss.metrics import rms_db_scorer
    >>> callable(rms_db_scorer)
    True
    """
    return -rms_error(y, estimator.predict(X), db=True)
