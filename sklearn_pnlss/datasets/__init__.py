"""Benchmark data: the Bouc-Wen hysteresis benchmark."""
from ._bouc_wen import (
    bouc_wen_oscillator,
    load_bouc_wen_official,
    make_bouc_wen,
    simulate_bouc_wen,
)

__all__ = [
    "bouc_wen_oscillator",
    "load_bouc_wen_official",
    "make_bouc_wen",
    "simulate_bouc_wen",
]
