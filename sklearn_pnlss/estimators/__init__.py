"""The estimators: BLA (linear), polynomial nonlinear state-space, and the
integrated-output wrapper for outputs that integrate."""
from .above_band import AboveBandRegressor
from .bla import BLAEstimator
from .decoupled import DecoupledPNLSSRegressor
from .integrated import IntegratedOutputRegressor
from .pnlss import PNLSSRegressor

__all__ = ["AboveBandRegressor", "BLAEstimator", "DecoupledPNLSSRegressor", "IntegratedOutputRegressor", "PNLSSRegressor"]
