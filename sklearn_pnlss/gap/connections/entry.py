"""Where a connection's force enters a structure, read off the measured
content above the excited band.

A multisine excites a band; a linear structure answers in that band only.
What the sensors carry above it is made by the structure's nonlinear
forces (harmonics of a cubic spring, the edges of a friction's stick-slip,
a clearance's impacts).  Such a force acts at its own points: a pair of
equal and opposite forces on the two points it joins, or one force on a
point tied to the ground.  Far enough above a structure's modes each point's
acceleration answers the force on it through its own mass (the mass line),
while a point one spring away receives it filtered by that spring, falling
as the square of the frequency.  So the content above the band is nearly
one direction across the sensors (one force, one shape), large at the
force's points and small elsewhere, and opposite in sign at the two points
of a pair.  Its place is read from that direction alone, with no nominal:
the support and the signs of the leading eigenvector of the sensors'
cross-power above the band, at the highest level (where the nonlinear
content stands furthest over the noise).

One point read alone is the ground, or a side the sensors do not see move
at those frequencies (much heavier than the point read): the reading
cannot tell the two apart, and says so.

Measured on new drawings of the simulated structures of
``benchmarks/gap_structures.py`` (``benchmarks/gap_entry.py``: chains of
2-5 masses and frames, one element at one joint, 1 % noise, 24 structures
per element): the right place in 93 of 96 backlash, dry-friction,
cubic-spring and quadratic-damping cases, none wrong, 3 not read; no place
read on the 24 linear ones, nor on 24 with a Bouc-Wen hysteresis, whose
smooth loop makes too little content there.
"""
from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from ...physics.structure import SENSOR_KINDS
from .locator import NOISE_FLOOR

__all__ = ["EntryReading", "read_entry"]

#: The content above the band over its noise (power, dB) a reading needs:
#: records of a linear structure give 0 +- 0.5 dB there.
SNR_DB = 10.0
#: Share of the leading direction's power the place's points must hold (a
#: support of one or two sensors): below, the force acts where no sensor is.
MIN_EXPLAINED = 0.9
#: A pair of points is read only where its second point adds this share of
#: the direction over the best single point, in the opposite sign: on the
#: drawings it was set on (``benchmarks/gap_entry.py --first-seed 3000
#: --seeds 16`` and ``--first-seed 5000 --seeds 10``), a point one spring
#: from a grounded force adds 0.08 at most (a frame), the second point of a
#: pair 0.13 at least.
PAIR_MARGIN = 0.1


@dataclass(frozen=True)
class EntryReading:
    """The leading direction of the content above the band, and the place
    it points at.

    Attributes
    ----------
    place : tuple of (str, str or None) or None
        The place read (second point None: the ground, or a side no sensor
        sees move above the band); None where the content is too weak
        (``SNR_DB``) or points at no candidate place (``MIN_EXPLAINED``).
    direction : ndarray of shape (n_sensors,)
        The leading direction (unit norm, its largest entry positive), as
        accelerations.
    snr_db : float
        Power of the content above the band over its noise, dB.
    explained : dict
        Each candidate place's share of the direction.
    record : int
        The record read (the highest input level).
    band : (float, float)
        The lines read, Hz.
    """

    place: tuple
    direction: np.ndarray
    snr_db: float
    explained: dict
    record: int
    band: tuple

    @property
    def clear(self):
        return self.place is not None

    def best(self, grounded):
        """The candidate place that holds most of the direction, among the
        points to the ground (``grounded``) or among the pairs; None if
        there is none."""
        return max((p for p in self.explained if (p[1] is None) == grounded), key=self.explained.get, default=None)

    @property
    def pair_gain(self):
        """What the best pair of points holds of the direction over the best
        single point (``PAIR_MARGIN`` is its threshold); None without both."""
        single, pair = self.best(True), self.best(False)
        return None if single is None or pair is None else self.explained[pair] - self.explained[single]

    def __str__(self):
        shape = ", ".join(f"{v:+.2f}" for v in self.direction)
        head = (f"content above the band ({self.band[0]:.0f}-{self.band[1]:.0f} Hz) {self.snr_db:.0f} dB over "
                f"the noise, direction across the sensors ({shape}): ")
        if self.place is None:
            return head + "no place read"
        a, b = self.place
        if b is None:
            return head + f"enters at {a} (from the ground, or from a side no sensor sees move there)"
        return head + f"enters between {a} and {b}"


def _to_acceleration(freqs, sensors):
    """The factor on each line and sensor that makes displacement, velocity
    or acceleration spectra accelerations, so that their directions
    compare."""
    order = np.array([SENSOR_KINDS.index(kind) for _, kind in sensors])  # 0, 1, 2: d, v, a
    return (2j * np.pi * freqs[:, None]) ** (2 - order)


def _share(direction, index, place):
    a, b = (index[p] if p is not None else None for p in place)
    if b is None:
        return direction[a] ** 2
    if direction[a] * direction[b] < 0:
        return direction[a] ** 2 + direction[b] ** 2
    return max(direction[a] ** 2, direction[b] ** 2)


def read_entry(spectra, sensors, band_top, places):
    """Read where the content above ``band_top`` enters.

    Parameters
    ----------
    spectra : PeriodSpectra
        The records' period-averaged spectra and their noise.
    sensors : sequence of (str, str)
        ``(point, kind)`` of each output.
    band_top : float
        Top of the excited band, Hz: the lines above it (to below the
        Nyquist frequency) are read.
    places : sequence of (str, str or None)
        The candidate places.

    Returns
    -------
    EntryReading
    """
    freqs = spectra.freqs
    lines = np.flatnonzero((freqs > band_top) & (freqs < spectra.fs / 2))
    record = int(np.argmax(np.sum(np.abs(spectra.U) ** 2, axis=(1, 2))))
    points = [point for point, _ in sensors]
    band = (float(freqs[lines[0]]), float(freqs[lines[-1]])) if lines.size else (band_top, band_top)
    if lines.size < 4 or len(set(points)) < len(points):  # one sensor per point, or no reading
        return EntryReading(None, np.zeros(len(points)), -np.inf, {}, record, band)
    factor = _to_acceleration(freqs[lines], sensors)
    Y = spectra.Y[record, lines] * factor
    # noise-free records (a simulation) are credited the locator's floor,
    # relative to each sensor's power in the band: a linear simulation's
    # rounding above the band is no content
    in_band = spectra.Y[record, (freqs > 0) & (freqs <= band_top)]
    floor = NOISE_FLOOR * np.mean(np.abs(in_band) ** 2, axis=0)
    noise = np.maximum(spectra.Y_noise[record, lines], floor) * np.abs(factor) ** 2
    power = Y.conj().T @ Y
    noise_power = np.sum(noise, axis=0)
    snr_db = 10 * np.log10(np.trace(power).real / max(np.sum(noise_power), np.finfo(float).tiny))
    _, vectors = np.linalg.eigh(power - np.diag(noise_power))
    leading = vectors[:, -1]
    leading = leading * np.exp(-1j * np.angle(leading[np.argmax(np.abs(leading))]))
    direction = leading.real / np.linalg.norm(leading.real)
    index = {p: i for i, p in enumerate(points)}
    readable = [tuple(p) for p in places if all(q is None or q in index for q in p)]
    explained = {p: float(_share(direction, index, p)) for p in readable}
    reading = EntryReading(None, direction, float(snr_db), explained, record, band)
    single, pair, gain = reading.best(True), reading.best(False), reading.pair_gain
    place = pair if single is None or (gain is not None and gain > PAIR_MARGIN) else single
    if place is None or snr_db < SNR_DB or explained[place] < MIN_EXPLAINED:
        return reading
    return replace(reading, place=place)
