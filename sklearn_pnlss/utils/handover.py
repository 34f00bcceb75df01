"""Hand-over between the stages of a Pipeline.

``make_pipeline(BLAEstimator(), PNLSSRegressor(), DecoupledPNLSSRegressor())``
fits each stage from the model of the stage before it. A stage's
``transform`` passes the input signals through unchanged and attaches the
fitted stage to them; the next stage's ``fit`` detaches it and starts from
it. The signals stay a plain array (or list) for everything else, so the
hand-over survives slicing, ``clone`` of the estimators (it is data, not a
parameter), pickling (the ``Pipeline(memory=...)`` cache) and joblib.

Held-out test signals travel the same way: :class:`HeldOutSignalList` (what
:func:`sklearn_pnlss.model_selection.held_out_signals` returns) knows which
of its signals are for training, so that an estimator given all of them
(``GridSearchCV``'s refit) fits the training signals only
(:func:`training_signals`).
"""
import numpy as np

from .validation import signal_layout

__all__ = ["HeldOutSignalList", "StageSignals", "StageSignalList", "attach_stage", "detach_stage", "training_signals"]


class StageSignals(np.ndarray):
    """An array of signals with the fitted stage that produced it."""

    def __new__(cls, X, stage):
        obj = np.asarray(X).view(cls)
        obj.stage = stage
        return obj

    def __array_finalize__(self, obj):
        self.stage = getattr(obj, "stage", None)

    def __reduce__(self):
        rebuild, args, state = super().__reduce__()
        return rebuild, args, (state, self.stage)

    def __setstate__(self, state):
        array_state, self.stage = state
        super().__setstate__(array_state)


class StageSignalList(list):
    """A list of signals (unequal lengths) with the fitted stage."""

    def __init__(self, signals, stage):
        super().__init__(signals)
        self.stage = stage

    def __reduce__(self):
        return (StageSignalList, (list(self), self.stage))


def attach_stage(X, stage):
    """``X`` (array or list of signals) with ``stage`` attached."""
    if signal_layout(X).kind == "list":
        return StageSignalList(X, stage)
    return StageSignals(X, stage)


def detach_stage(X):
    """``(signals, stage)``; ``stage`` is None for plain input."""
    stage = getattr(X, "stage", None)
    if isinstance(X, StageSignals):
        return np.asarray(X), stage
    if isinstance(X, StageSignalList):
        return list(X), stage
    return X, None


class HeldOutSignalList(list):
    """Training and held-out test signals in one list; ``train`` holds the
    indices of the training signals.

    Splitting it (scikit-learn's cross-validation indexes it) gives plain
    lists: only the whole list carries the split.
    """

    def __init__(self, signals, train):
        super().__init__(signals)
        self.train = np.asarray(train, dtype=int)

    def __reduce__(self):
        return (HeldOutSignalList, (list(self), self.train))


def training_signals(X, y):
    """``(X, y)``, or only their training signals when ``y`` is a whole
    :class:`HeldOutSignalList`: an estimator never fits held-out test
    signals, even when a search refits it on everything it was given.
    ``y`` decides because a Pipeline hands it to every stage unchanged."""
    if not isinstance(y, HeldOutSignalList):
        return X, y
    X_list = X if isinstance(X, (list, tuple)) else list(np.asarray(X))
    if len(X_list) != len(y):
        return X, y  # not the list held_out_signals made; validation says what is wrong
    return [X_list[i] for i in y.train], [y[i] for i in y.train]
