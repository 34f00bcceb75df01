"""The estimators: BLA (linear) and polynomial nonlinear state-space."""
from .bla import BLAEstimator
from .decoupled import DecoupledPNLSSRegressor
from .pnlss import PNLSSRegressor

__all__ = ["BLAEstimator", "DecoupledPNLSSRegressor", "PNLSSRegressor"]
