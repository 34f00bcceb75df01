"""The estimators: BLA (linear), polynomial nonlinear state-space, the
integrated-output wrapper for outputs that integrate, and the wrapper that
adds the response above the excited band, and the average of one model
fitted from several random starts."""
from .above_band import AboveBandRegressor
from .averaged import AveragedRegressor
from .bla import BLAEstimator
from .decoupled import DecoupledPNLSSRegressor
from .integrated import IntegratedOutputRegressor
from .lru_above_band import LRUAboveBandRegressor
from .pnlss import PNLSSRegressor

__all__ = ["AboveBandRegressor", "AveragedRegressor", "BLAEstimator", "DecoupledPNLSSRegressor", "IntegratedOutputRegressor", "LRUAboveBandRegressor", "PNLSSRegressor"]
