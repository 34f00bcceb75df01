"""The estimators: BLA (linear), and later PNLSS and decoupled PNLSS."""
from .bla import BLAEstimator

__all__ = ["BLAEstimator"]
