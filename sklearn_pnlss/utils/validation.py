"""Validation of input-output signals in the library's convention.

A collection of signals may be given as

* a 3-D array ``(n_signals, n_samples, n_channels)``,
* a list (or tuple) of 1-D or 2-D numpy arrays (lengths may differ),
* one signal as a 2-D array ``(n_samples, n_channels)`` or a 1-D array.

Nested plain Python lists (``X.tolist()``) are read as an array, not as a
list of signals: only a list whose items are arrays is a list of signals.

Everything is turned into a list of 2-D float64 arrays, and the layout is
remembered so that predictions come back in the layout of the input.
"""
from dataclasses import dataclass

import numpy as np
from sklearn.utils.validation import check_array, validate_data

__all__ = [
    "SignalLayout",
    "as_signal_list",
    "signal_layout",
    "validate_signals",
    "restore_layout",
    "is_periodic",
    "check_period",
]


@dataclass(frozen=True)
class SignalLayout:
    """How a collection of signals was passed: ``"3d"``, ``"list"``,
    ``"2d"`` (one signal, channels in columns) or ``"1d"`` (one signal, one
    channel)."""

    kind: str


def _is_signal_list(X):
    return isinstance(X, (list, tuple)) and any(hasattr(s, "shape") for s in X)


def signal_layout(X):
    """The :class:`SignalLayout` in which ``X`` was passed."""
    if _is_signal_list(X):
        return SignalLayout("list")
    if hasattr(X, "toarray") or hasattr(X, "tocsr"):
        return SignalLayout("sparse")
    try:
        ndim = np.asarray(X).ndim
    except ValueError:  # nested lists of unequal lengths
        return SignalLayout("ragged")
    return SignalLayout({3: "3d", 2: "2d", 1: "1d"}.get(ndim, "invalid"))


def _finite_2d(signal, name, index, min_samples):
    """One signal as a finite float64 2-D array (samples, channels)."""
    where = name if index is None else f"{name}[{index}]"
    try:
        arr = check_array(
            signal,
            ensure_2d=False,
            dtype=np.float64,
            ensure_all_finite=False,
            input_name=where,
            ensure_min_samples=1,
        )
    except (ValueError, TypeError) as exc:
        # scikit-learn's messages ("Found array with 0 sample(s)", "could not
        # convert string to float") do not say which argument is wrong.
        raise (ValueError if isinstance(exc, ValueError) else TypeError)(f"{where}: {exc}") from exc
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise ValueError(
            f"{where} must be a 1-D or 2-D signal (n_samples, n_channels); "
            f"got an array with {arr.ndim} dimensions."
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(
            f"{where} contains NaN or infinity; remove or interpolate the "
            "bad samples before fitting or predicting."
        )
    if 1 < arr.shape[0] < arr.shape[1]:
        # The commonest mistake: n_signals single-channel signals as a 2-D
        # (n_signals, n_samples) array, read as one signal with n_samples
        # channels. No measurement has more channels than samples.
        raise ValueError(
            f"{where} has shape {arr.shape}, read as {arr.shape[0]} samples of {arr.shape[1]} "
            "channels: a signal is (n_samples, n_channels). For "
            f"{arr.shape[0]} single-channel signals of {arr.shape[1]} samples, add the channel "
            f"axis: {name}[..., None] (shape {(arr.shape[0], arr.shape[1], 1)}); for one signal, "
            f"transpose it ({name}.T)."
        )
    if arr.shape[0] < min_samples:
        raise ValueError(
            f"{where} has {arr.shape[0]} sample(s); at least {min_samples} "
            "are needed (n_samples = 1 is not a signal)."
        )
    if arr.shape[1] == 0:
        raise ValueError(f"{where} has 0 channels; at least one is needed.")
    return arr


def as_signal_list(X, *, name="X", min_samples=2):
    """Turn any accepted signal layout into a list of 2-D float arrays.

    Parameters
    ----------
    X : array-like or list of array-like
        Signals in one of the accepted layouts (see module docstring).
    name : str, default="X"
        Argument name used in error messages.
    min_samples : int, default=2
        Minimum number of samples per signal.

    Returns
    -------
    signals : list of ndarray of shape (n_samples_i, n_channels)
    layout : SignalLayout
    """
    if hasattr(X, "toarray") or hasattr(X, "tocsr"):
        raise TypeError(
            f"{name} is a sparse matrix; signals must be dense arrays "
            "(call .toarray() first)."
        )
    if isinstance(X, (list, tuple)) and len(X) == 0:
        raise ValueError(f"{name} is an empty list; pass at least one signal.")
    layout = signal_layout(X)
    if layout.kind == "list":
        if len(X) == 0:
            raise ValueError(f"{name} is an empty list; pass at least one signal.")
        signals = [_finite_2d(s, name, i, min_samples) for i, s in enumerate(X)]
    elif layout.kind == "3d":
        arr = np.asarray(X, dtype=np.float64) if not hasattr(X, "dtype") else np.asarray(X)
        if arr.shape[0] == 0:
            raise ValueError(f"{name} holds 0 signals; pass at least one signal.")
        signals = [_finite_2d(s, name, i, min_samples) for i, s in enumerate(arr)]
    elif layout.kind in ("2d", "1d"):
        signals = [_finite_2d(X, name, None, min_samples)]
    elif layout.kind == "ragged":
        raise ValueError(
            f"{name} is a nested list of unequal lengths; pass signals of unequal "
            "lengths as a list of numpy arrays, one per signal."
        )
    else:
        raise ValueError(
            f"{name} must be a 3-D array (n_signals, n_samples, n_channels), a "
            "list of 1-D/2-D signals, or one 1-D/2-D signal; got an array with "
            f"{np.ndim(X)} dimensions."
        )
    n_channels = {s.shape[1] for s in signals}
    if len(n_channels) > 1:
        raise ValueError(
            f"All signals in {name} must have the same number of channels; got "
            f"{sorted(n_channels)}."
        )
    return signals, layout


def _check_n_features(estimator, n_features, reset, layout):
    if reset:
        estimator.n_features_in_ = n_features
        return
    expected = getattr(estimator, "n_features_in_", None)
    if expected is not None and n_features != expected:
        hint = ""
        if layout.kind == "1d":
            hint = (
                " A 1-D X is read as one signal with one input: Reshape your "
                "data to (n_samples, n_inputs) for one multi-input signal."
            )
        raise ValueError(
            f"X has {n_features} features, but {type(estimator).__name__} is "
            f"expecting {expected} features as input (one per input channel).{hint}"
        )


def validate_signals(estimator, X, y=None, *, reset=True, min_samples=2):
    """Validate X (and y) for an estimator's fit or predict.

    Sets ``n_features_in_`` (number of inputs) and, for a single 2-D signal
    given as a DataFrame, ``feature_names_in_``, the scikit-learn way.

    Returns
    -------
    X_list : list of ndarray (n_samples_i, n_inputs)
    y_list : list of ndarray (n_samples_i, n_outputs) or None
    layout : SignalLayout of X
    """
    layout = signal_layout(X)
    if layout.kind == "2d":
        # A single 2-D signal is a plain sklearn X: let sklearn handle
        # feature names and the n_features_in_ bookkeeping.
        try:
            validate_data(
                estimator, X, reset=reset, ensure_all_finite=False, dtype=None,
                ensure_min_samples=1, skip_check_array=False,
            )
        except (ValueError, TypeError) as exc:
            if str(exc).startswith("X "):
                raise
            raise (ValueError if isinstance(exc, ValueError) else TypeError)(f"X: {exc}") from exc
    X_list, layout = as_signal_list(X, name="X", min_samples=min_samples)
    if layout.kind != "2d":
        _check_n_features(estimator, X_list[0].shape[1], reset, layout)
        if reset and hasattr(estimator, "feature_names_in_"):
            del estimator.feature_names_in_
    if y is None:
        return X_list, None, layout
    y_list, _ = as_signal_list(y, name="y", min_samples=min_samples)
    if len(y_list) != len(X_list):
        raise ValueError(
            f"X holds {len(X_list)} signal(s) but y holds {len(y_list)}; pass "
            "one output signal per input signal."
        )
    for i, (xs, ys) in enumerate(zip(X_list, y_list)):
        if xs.shape[0] != ys.shape[0]:
            raise ValueError(
                f"Signal {i}: X has {xs.shape[0]} samples but y has "
                f"{ys.shape[0]}; input and output must have the same length."
            )
    return X_list, y_list, layout


def restore_layout(signals, layout, *, squeeze_1d=False):
    """Put predicted signals back in the layout the input came in.

    ``squeeze_1d`` returns a 1-D array for a single-output single signal (when
    the estimator was fitted on a 1-D ``y``).
    """
    if layout.kind == "3d":
        return np.stack(signals)
    if layout.kind == "list":
        return list(signals)
    out = signals[0]
    if squeeze_1d and out.shape[1] == 1:
        return out[:, 0]
    return out


def check_period(period, name="period"):
    """Validate a period given in samples (None allowed)."""
    if period is None:
        return None
    if isinstance(period, (bool, np.bool_)) or not isinstance(
        period, (int, np.integer)
    ):
        raise TypeError(f"{name} must be a positive integer number of samples or None; got {period!r}.")
    if period < 2:
        raise ValueError(f"{name} must be at least 2 samples; got {period}.")
    return int(period)


def is_periodic(n_samples, period):
    """Whether a signal of ``n_samples`` is taken as periodic steady state."""
    return period is not None and n_samples >= period and n_samples % period == 0
