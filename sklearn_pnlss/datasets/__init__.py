"""Benchmark data: the Bouc-Wen hysteresis benchmark (simulated and official
files) and the measured F-16 ground vibration test."""
from ._bouc_wen import (
    bouc_wen_oscillator,
    load_bouc_wen_official,
    make_bouc_wen,
    simulate_bouc_wen,
)
from ._f16 import load_f16

__all__ = [
    "bouc_wen_oscillator",
    "load_bouc_wen_official",
    "load_f16",
    "make_bouc_wen",
    "simulate_bouc_wen",
]
