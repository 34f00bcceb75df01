"""Physical simulators: an oscillator with nonlinear force elements, and a
structure of several degrees of freedom with nonlinear connections.

The integrator, resampling and noise reproduce the procedure behind the
Bouc-Wen benchmark data (see :func:`sklearn_pnlss.datasets.simulate_bouc_wen`).
"""
from .forces import (
    BoucWen,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    CustomForce,
    DeadZoneSpring,
    ForceElement,
    QuadraticDamping,
    QuadraticStiffness,
    SeriesDamper,
    StiffnessDrift,
)
from .oscillator import FineSimulation, Oscillator, band_limited_noise
from .resampling import decimate_fir, fir_decimation_filter, upsample_fft
from .structure import SENSOR_KINDS, Connection, Structure, StructureSimulation

__all__ = [
    "BoucWen",
    "Connection",
    "CoulombFriction",
    "CoupledMass",
    "CubicStiffness",
    "CustomForce",
    "DeadZoneSpring",
    "FineSimulation",
    "ForceElement",
    "Oscillator",
    "QuadraticDamping",
    "QuadraticStiffness",
    "SENSOR_KINDS",
    "SeriesDamper",
    "StiffnessDrift",
    "Structure",
    "StructureSimulation",
    "band_limited_noise",
    "decimate_fir",
    "fir_decimation_filter",
    "upsample_fft",
]
