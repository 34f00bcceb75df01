"""Error measures used across the field, and scorers that apply any metric
over whole signals.

scikit-learn's string scorers (``scoring="r2"``) call their metric on the
signals as they are, 3-D arrays, which its metrics refuse: the search then
records NaN with a warning. :func:`signal_scorer` gives the same scorers by
name, applied over whole signals (all samples of all signals pooled, one
column per output), and :func:`make_signal_scorer` wraps any metric
function the same way.
"""
import numpy as np

from .utils.validation import as_signal_list

__all__ = [
    "fit_percent",
    "make_signal_scorer",
    "max_error",
    "nrmse",
    "nrmse_by_band",
    "rms_db_scorer",
    "rms_error",
    "signal_scorer",
    "to_db",
]


def to_db(value):
    """Amplitude in decibels, ``20 log10(value)``."""
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(value)


def rms_error(y_true, y_pred, db=False, skip=0):
    """Root-mean-square simulation error over all signals, samples and outputs.

    Signals are concatenated, so a long signal weighs more than a short one,
    exactly as if they were one record.

    Parameters
    ----------
    y_true, y_pred : array-like or list of array-like
        Signals in the library convention (3-D array, list, or one signal).
    db : bool, default=False
        Return ``20 log10(rms)`` instead of the rms in the signal's units.
    skip : int, default=0
        Samples left out at the start of every signal: the
        state-initialisation window a benchmark's official score skips
        (``load_benchmark(...).skip``).

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
    true, pred = _pooled(y_true, y_pred, skip)
    value = np.sqrt(np.mean((true - pred) ** 2))
    return float(to_db(value)) if db else float(value)


def _pooled(y_true, y_pred, skip=0):
    """All samples of all signals but the first ``skip`` of each,
    (n_total_samples, n_outputs), of both."""
    true, pred = _signal_pairs(y_true, y_pred, skip)
    skip = int(skip)
    return np.concatenate([a[skip:] for a in true]), np.concatenate([b[skip:] for b in pred])


def _signal_pairs(y_true, y_pred, skip=0):
    """Both as lists of 2-D signals, checked to match in number and shapes
    and to be longer than ``skip``."""
    true, _ = as_signal_list(y_true, name="y_true", min_samples=1)
    pred, _ = as_signal_list(y_pred, name="y_pred", min_samples=1)
    if len(true) != len(pred) or any(a.shape != b.shape for a, b in zip(true, pred)):
        raise ValueError(
            "y_true and y_pred must hold the same number of signals with the "
            f"same shapes; got {[a.shape for a in true]} and "
            f"{[b.shape for b in pred]}."
        )
    skip = int(skip)
    if skip < 0 or any(a.shape[0] <= skip for a in true):
        raise ValueError(
            f"skip={skip} must be non-negative and shorter than every signal "
            f"(lengths {[a.shape[0] for a in true]})."
        )
    return true, pred


def nrmse(y_true, y_pred, skip=0):
    """Normalised rms error: ``||y - y_hat|| / ||y - mean(y)||`` per output
    over all signals, averaged over the outputs (0 is perfect, 1 is no
    better than the mean; MATLAB's ``goodnessOfFit(..., "NRMSE")``; the
    rms error over the standard deviation, as the field's loader scores).
    ``skip``: samples left out at the start of every signal (see
    :func:`rms_error`).

    Examples
    --------
    >>> import numpy as np
    >>> y = np.array([1.0, -1.0, 1.0, -1.0])
    >>> round(nrmse(y, 0.9 * y), 12)
    0.1
    """
    true, pred = _pooled(y_true, y_pred, skip)
    spread = np.linalg.norm(true - true.mean(axis=0), axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.mean(np.linalg.norm(true - pred, axis=0) / spread))


def nrmse_by_band(y_true, y_pred, fs, edges, skip=0):
    """Where in frequency the simulation error lies: the normalised rms
    error of each output split over frequency bands.

    Each signal's error and output (after ``skip``) go through one DFT;
    band ``k`` holds the bins with ``edges[k] <= f < edges[k + 1]``. Its
    value is ``sqrt(error power in the band / output power)``, per output,
    pooled over the signals: by Parseval the squares of a row's bands add
    up to the squared rms error over ``rms(y)`` (the mean is not removed,
    so the total is :func:`nrmse` exactly only for zero-mean outputs). A
    model whose error sits where the input has no power (harmonics,
    resonances rung by a nonlinearity) shows it here, not in the total.

    Parameters
    ----------
    y_true, y_pred : array-like or list of array-like
        Signals in the library convention.
    fs : float
        Sampling frequency (Hz).
    edges : sequence of float
        Increasing band edges in Hz; bins outside ``[edges[0], edges[-1])``
        count in no band.
    skip : int, default=0
        Samples left out at the start of every signal.

    Returns
    -------
    ndarray of shape (len(edges) - 1, n_outputs)

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000) / 100.0
    >>> y = np.sin(2 * np.pi * 5 * t)
    >>> y_hat = y + 0.1 * np.sin(2 * np.pi * 30 * t)   # an error at 30 Hz only
    >>> nrmse_by_band(y, y_hat, fs=100.0, edges=[0, 10, 50.1]).round(6).ravel().tolist()
    [0.0, 0.1]
    """
    edges = np.asarray(edges, dtype=float)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0):
        raise ValueError(f"edges must be an increasing sequence of at least two frequencies; got {edges!r}.")
    true, pred = _signal_pairs(y_true, y_pred, skip)
    skip = int(skip)
    error_power = np.zeros((edges.size - 1, true[0].shape[1]))
    output_power = np.zeros(true[0].shape[1])
    for a, b in zip(true, pred):
        Y = np.fft.rfft(a[skip:], axis=0)
        E = np.fft.rfft(a[skip:] - b[skip:], axis=0)
        n = a.shape[0] - skip
        # Parseval per signal (1 / n), the interior bins of the one-sided
        # spectrum standing for their negative-frequency twins too
        bins = np.arange(Y.shape[0])
        twice = np.where((bins == 0) | (2 * bins == n), 1.0, 2.0)[:, None] / n
        output_power += (twice * np.abs(Y) ** 2).sum(axis=0)
        band = np.searchsorted(edges, np.fft.rfftfreq(n, 1.0 / fs), side="right") - 1
        inside = (band >= 0) & (band < edges.size - 1)
        np.add.at(error_power, band[inside], twice[inside] * np.abs(E[inside]) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(error_power / output_power)


def fit_percent(y_true, y_pred, skip=0):
    """The "fit" of MATLAB's ``compare``: ``100 (1 - NRMSE)`` in percent
    (100 is perfect, 0 no better than the mean, negative worse). ``skip``:
    see :func:`rms_error`.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.array([1.0, -1.0, 1.0, -1.0])
    >>> round(fit_percent(y, 0.9 * y), 6)
    90.0
    """
    return 100.0 * (1.0 - nrmse(y_true, y_pred, skip))


def max_error(y_true, y_pred):
    """Largest absolute simulation error over all signals, samples and
    outputs (in the units of y).

    Examples
    --------
    >>> max_error([0.0, 1.0, 2.0], [0.0, 1.5, 1.9])
    0.5
    """
    true, pred = _pooled(y_true, y_pred)
    return float(np.max(np.abs(true - pred)))


class _SignalScorer:
    """``sign * metric(y, estimator.predict(X))`` over pooled signals (with
    ``init_window``: each signal started from the state its first outputs
    show, and those samples left out)."""

    def __init__(self, metric, sign, name, kwargs, init_window=0):
        self.metric, self.sign, self.name, self.kwargs = metric, sign, name, kwargs
        self.init_window = int(init_window)

    def __call__(self, estimator, X, y, sample_weight=None):
        if sample_weight is not None:
            raise ValueError("sample_weight is not supported by signal scorers; pass None.")
        if self.init_window:
            windows = [Y[: self.init_window] for Y in as_signal_list(y, name="y", min_samples=1)[0]]
            pred = estimator.predict(X, y_init=windows)
        else:
            pred = estimator.predict(X)
        true, pred = _pooled(y, pred, self.init_window)
        return self.sign * float(self.metric(true, pred, **self.kwargs))

    def __repr__(self):
        window = f", init_window={self.init_window}" if self.init_window else ""
        if self.name:
            return f"signal_scorer({self.name!r}{window})"
        return f"make_signal_scorer({self.metric.__name__}{window})"


def make_signal_scorer(metric, *, greater_is_better=True, init_window=0, **kwargs):
    """A scorer for ``GridSearchCV`` / ``cross_val_score`` that applies a
    metric over whole signals.

    The predictions and the true outputs of all held-out signals are pooled
    into two arrays of shape (n_total_samples, n_outputs), the form every
    scikit-learn regression metric takes, and ``metric(y_true, y_pred,
    **kwargs)`` is applied to them.

    Parameters
    ----------
    metric : callable
        ``metric(y_true, y_pred, **kwargs) -> float``, e.g.
        :func:`sklearn.metrics.r2_score` or :func:`nrmse`.
    greater_is_better : bool, default=True
        False for an error (the scorer then returns minus the metric, as
        scikit-learn's ``neg_*`` scorers do).
    init_window : int, default=0
        Samples at the start of each held-out signal whose measured outputs
        set its initial state (``predict(X, y_init=...)``) and which the
        score leaves out: the field's protocol for records that do not
        start from rest (``load_benchmark(...).skip``).
    **kwargs
        Passed on to ``metric``.

    Returns
    -------
    scorer : callable ``(estimator, X, y) -> float``

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from sklearn.metrics import mean_absolute_error
    >>> X = np.ones((2, 4, 1))
    >>> model = SimpleNamespace(predict=lambda X: 0.5 * X)   # stands for a fitted estimator
    >>> make_signal_scorer(mean_absolute_error, greater_is_better=False)(model, X, X)
    -0.5
    """
    return _SignalScorer(metric, 1.0 if greater_is_better else -1.0, None, kwargs, init_window)


def _scorers():
    from sklearn import metrics as skm

    return {
        "r2": (skm.r2_score, 1.0),
        "explained_variance": (skm.explained_variance_score, 1.0),
        "neg_mean_squared_error": (skm.mean_squared_error, -1.0),
        "neg_root_mean_squared_error": (lambda t, p: np.sqrt(skm.mean_squared_error(t, p)), -1.0),
        "neg_mean_absolute_error": (skm.mean_absolute_error, -1.0),
        "neg_max_error": (lambda t, p: max_error(t, p), -1.0),
        "neg_nrmse": (nrmse, -1.0),
        "fit_percent": (fit_percent, 1.0),
        "neg_rms_db": (lambda t, p: rms_error(t, p, db=True), -1.0),
    }


def signal_scorer(name, *, init_window=0):
    """scikit-learn's scorer ``name``, applied over whole signals.

    For ``scoring=signal_scorer("r2")`` where scikit-learn habits would
    write ``scoring="r2"`` (which gives NaN on signals: see the module
    docstring).

    Parameters
    ----------
    name : str
        One of "r2", "explained_variance", "neg_mean_squared_error",
        "neg_root_mean_squared_error", "neg_mean_absolute_error",
        "neg_max_error" (scikit-learn's names), and the field's
        "fit_percent" (MATLAB's ``compare``), "neg_nrmse" and "neg_rms_db"
        (minus the rms error in dB, as :func:`rms_db_scorer`). Higher is
        better for all.
    init_window : int, default=0
        As in :func:`make_signal_scorer`: held-out signals start from the
        state their first ``init_window`` outputs show, left out of the
        score.

    Returns
    -------
    scorer : callable ``(estimator, X, y) -> float``

    Examples
    --------
    >>> signal_scorer("r2")
    signal_scorer('r2')
    """
    table = _scorers()
    if name not in table:
        raise ValueError(f"Unknown signal scorer {name!r}; choose one of {sorted(table)}.")
    metric, sign = table[name]
    return _SignalScorer(metric, sign, name, {}, init_window)


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
