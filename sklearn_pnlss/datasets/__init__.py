"""Benchmark data: the Bouc-Wen hysteresis benchmark (simulated and official
files), the measured F-16 ground vibration test, and the field's other
measured benchmarks by their official splits."""
from ._bouc_wen import (
    bouc_wen_oscillator,
    load_bouc_wen_official,
    make_bouc_wen,
    simulate_bouc_wen,
)
from ._f16 import load_f16
from ._field import from_io_data, load_benchmark

__all__ = [
    "bouc_wen_oscillator",
    "from_io_data",
    "load_benchmark",
    "load_bouc_wen_official",
    "load_f16",
    "make_bouc_wen",
    "simulate_bouc_wen",
]
