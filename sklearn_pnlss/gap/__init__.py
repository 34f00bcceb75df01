"""Sim-to-real gap diagnosis: where a physical simulator misses the
measurements, which unmodelled effect causes it, how far adding it shrinks
the gap (see :class:`GapDiagnosis`)."""
from .verdict.decision import RankedEffect
from .diagnosis import GapDiagnosis
from .candidates.effect import EffectTerms
from .candidates.effects import Effect, Scales, default_effects
from .connections.diagnosis import StructuralGapDiagnosis, StructuralGapReport
from .connections.locator import ConnectionCandidate, ConnectionLocator
from .linear_nominal import linear_nominal
from .modal_nominal import modal_nominal
from .report import GapReport
from .results import ChannelDelay

__all__ = ["GapDiagnosis", "GapReport", "RankedEffect", "ChannelDelay", "Effect", "EffectTerms", "Scales",
           "default_effects", "linear_nominal", "modal_nominal", "ConnectionLocator", "ConnectionCandidate",
           "StructuralGapDiagnosis", "StructuralGapReport"]
