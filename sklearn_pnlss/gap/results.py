"""Typed results of a diagnosis, read by its report and its user: what
the fit found in the measurement chain, and where the gap lies."""
from dataclasses import dataclass
from typing import Dict, List, NamedTuple, Optional

import numpy as np

__all__ = ["ChannelDelay", "GapLocation", "FrequencyGap", "Band", "LineKindGap", "AmplitudeGap", "LevelGap",
           "LevelBin", "InputLevel", "ForceMap", "MotionSamples", "TimeGap", "SweepGap", "SweepWindow", "Drift"]


class ChannelDelay(NamedTuple):
    """A delay between the force and displacement channels that the
    training data carry (a sensor's, an anti-alias filter's): a property of
    the measurement chain, fitted with every candidate.

    Attributes
    ----------
    delay_s : float
        The delay, seconds (positive: the displacement lags the force).
    samples : float
        The same in samples of the data: the start of every candidate's
        delay parameter.
    gain_db : float
        How much freeing the delay improved the fit it was found on, dB.
    found_on : str
        That fit: ``"recalibration"`` (the nominal refitted, the first
        look) or the candidate it hid behind (a strong nonlinearity that
        the nominal's refit could not follow).
    """

    delay_s: float
    samples: float
    gain_db: float
    found_on: str


# -- where the gap lies (see sklearn_pnlss.gap.where.locate_gap) -------------------
# Dataclasses, so that ``dataclasses.asdict`` gives the report's plain
# dictionaries (GapReport.to_dict).

@dataclass(frozen=True)
class Band:
    """The gap in one frequency band of the periodic validation signals:
    dB of the power summed over its lines (``|X_k|^2 / N`` per line, one
    period), and how many of its lines the gap sets significantly above
    the noise."""

    f_lo: float
    f_hi: float
    gap_db: float
    noise_db: float
    distortion_db: Optional[float]
    n_lines: int
    n_significant: int


@dataclass(frozen=True)
class LineKindGap:
    """The gap at one kind of line (excited, odd or even not excited)."""

    n_lines: int
    n_significant: int
    gap_db: float
    noise_db: float


@dataclass(frozen=True)
class FrequencyGap:
    """The gap against frequency: per DFT line (``frequency``,
    ``gap_power``, ``noise_power``, the training data's nonlinear
    ``distortion_power`` or None, ``line_kind``: 0 DC, 1 excited, 2 odd, 3
    even not excited, ``significant``), per band, per line kind, and
    whether the input leaves detection lines to read."""

    frequency: np.ndarray
    gap_power: np.ndarray
    noise_power: np.ndarray
    distortion_power: Optional[np.ndarray]
    line_kind: np.ndarray
    significant: np.ndarray
    bands: List[Band]
    line_kinds: Dict[str, LineKindGap]
    detection_lines: bool


@dataclass(frozen=True)
class LevelBin:
    """The gap (mean square, dB) over the samples whose level is in
    ``[lo, hi)``; None for an empty bin."""

    lo: float
    hi: float
    gap_db: Optional[float]


@dataclass(frozen=True)
class LevelGap:
    """The gap against the level of one signal (quantile bins), with the
    noise floor's level (None without one)."""

    bins: List[LevelBin]
    noise_db: Optional[float]


@dataclass(frozen=True)
class InputLevel:
    """One signal's input rms and its gap relative to its output power."""

    set: str
    input_rms: float
    relative_gap_db: float


@dataclass(frozen=True)
class AmplitudeGap:
    """The gap against displacement and velocity level, and per input
    level (``several_levels``: the inputs differ by more than 20 %)."""

    displacement: LevelGap
    velocity: LevelGap
    input_levels: List[InputLevel]
    several_levels: bool


@dataclass(frozen=True)
class MotionSamples:
    """The measured motion and the force the nominal leaves unbalanced
    along it, sample by sample (all signals concatenated)."""

    displacement: np.ndarray
    velocity: np.ndarray
    force: np.ndarray


@dataclass(frozen=True)
class ForceMap:
    """The mean missing force over the (displacement, velocity) plane
    (NaN where a cell has too few samples); stateful nominal elements are
    left out of the nominal's force (their states are not measured)."""

    displacement_edges: np.ndarray
    velocity_edges: np.ndarray
    force: np.ndarray
    count: np.ndarray
    missing_force_rms: float
    stateful_nominal_left_out: bool
    samples: MotionSamples


@dataclass(frozen=True)
class SweepWindow:
    """The gap and the output in one window of a sweep, at the input's
    instantaneous frequency there."""

    t: float
    frequency: float
    gap_db: float
    output_db: float


@dataclass(frozen=True)
class SweepGap:
    """The gap along one validation sweep (signal index ``signal``)."""

    signal: int
    windows: List[SweepWindow]


@dataclass(frozen=True)
class Drift:
    """How much the training response changes from its first period, over
    what noise alone gives, per later period; its slope per period, and
    whether the last change is over twice the noise's."""

    change_vs_noise_db: List[float]
    slope_per_period: float
    drifting: bool


@dataclass(frozen=True)
class TimeGap:
    """The gap along sweeps and the drift over the training periods (None
    without a noise floor or three periods)."""

    sweeps: List[SweepGap]
    drift: Optional[Drift]


@dataclass(frozen=True)
class GapLocation:
    """Where a nominal simulator misses the validation signals: in
    frequency (None without periodic validation signals or a noise floor),
    in amplitude, over the (displacement, velocity) plane, and in time."""

    frequency: Optional[FrequencyGap]
    amplitude: AmplitudeGap
    state_plane: ForceMap
    time: TimeGap
