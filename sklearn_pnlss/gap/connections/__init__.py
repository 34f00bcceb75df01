"""Where in a structure the simulator is wrong: connections between sensed
points, fitted to the nominal's error (see :class:`ConnectionLocator`)."""
from .laws import LAW_NAMES, ForceLaw, force_laws
from .diagnosis import StructuralGapDiagnosis, StructuralGapReport
from .locator import ConnectionCandidate, ConnectionLocator
from .refine import ConnectionFit
from .spectra import PeriodSpectra

__all__ = ["StructuralGapDiagnosis", "StructuralGapReport", "ConnectionFit", "ConnectionLocator", "ConnectionCandidate", "ForceLaw", "force_laws", "LAW_NAMES", "PeriodSpectra"]
