"""The estimators: BLA (linear), polynomial nonlinear state-space, the
integrated-output wrapper for outputs that integrate, and the wrapper that
adds the response above the excited band."""
from .above_band import AboveBandRegressor
from .bla import BLAEstimator
from .decoupled import DecoupledPNLSSRegressor
from .integrated import IntegratedOutputRegressor
from .pnlss import PNLSSRegressor

__all__ = ["AboveBandRegressor", "BLAEstimator", "DecoupledPNLSSRegressor", "IntegratedOutputRegressor", "PNLSSRegressor"]
