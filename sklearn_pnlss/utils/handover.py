"""Hand-over between the stages of a Pipeline.

``make_pipeline(BLAEstimator(), PNLSSRegressor(), DecoupledPNLSSRegressor())``
fits each stage from the model of the stage before it. A stage's
``transform`` passes the input signals through unchanged and attaches the
fitted stage to them; the next stage's ``fit`` detaches it and starts from
it. The signals stay a plain array (or list) for everything else, so the
hand-over survives slicing, ``clone`` of the estimators (it is data, not a
parameter), pickling (the ``Pipeline(memory=...)`` cache) and joblib.
"""
import numpy as np

from .validation import signal_layout

__all__ = ["StageSignals", "StageSignalList", "attach_stage", "detach_stage"]


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
