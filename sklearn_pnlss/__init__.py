"""Nonlinear system identification with scikit-learn's API."""
from importlib.metadata import PackageNotFoundError, version

from .estimators import AboveBandRegressor, AveragedRegressor, BLAEstimator, DecoupledPNLSSRegressor, IntegratedOutputRegressor, LRUAboveBandRegressor, PNLSSRegressor
from .statespace.model_base import DivergenceError
from .statespace.scaled import ScaledModel

try:
    __version__ = version("sklearn_pnlss")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = ["AboveBandRegressor", "AveragedRegressor", "BLAEstimator", "DecoupledPNLSSRegressor", "DivergenceError", "IntegratedOutputRegressor", "LRUAboveBandRegressor", "PNLSSRegressor", "ScaledModel", "__version__"]
