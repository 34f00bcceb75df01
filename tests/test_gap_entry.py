"""Where a connection's force enters, read off the content above the
excited band (sklearn_pnlss.gap.connections.entry)."""
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

from sklearn_pnlss.gap.connections.entry import SNR_DB, read_entry
from sklearn_pnlss.gap.connections.spectra import PeriodSpectra
from sklearn_pnlss.physics import Connection, CoulombFriction, CubicStiffness, DeadZoneSpring, Structure

POINTS = ["base", "middle", "tip"]
M, K = np.diag([3.0, 2.0, 1.0]), 5e4 * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
C = 1e-4 * K + 0.5 * M
FS, PERIOD, TOP = 200.0, 4096, 80.0
PLACES = [*combinations(POINTS, 2), *((p, None) for p in POINTS)]
F16 = Path(__file__).resolve().parents[2] / "shared" / "data" / "f16"


def spectra(connections, kind="acceleration", level=30.0, seed=0, noise=0.01):
    """Two periods of a 1-80 Hz multisine on the base, white noise of
    ``noise`` times each channel's rms."""
    rng = np.random.default_rng(seed)
    spectrum = np.zeros(PERIOD // 2 + 1, complex)
    lines = np.arange(20, int(TOP / FS * PERIOD), 2)
    spectrum[lines] = np.exp(2j * np.pi * rng.random(lines.size))
    u = np.fft.irfft(spectrum, PERIOD)
    u *= level / u.std()
    sensors = [(p, kind) for p in POINTS]
    y = Structure(M, C, K, points=POINTS, connections=connections).simulate(
        u, fs=FS, inputs="base", sensors=sensors, periodic=True, oversampling=20, decimation=(4, 5))
    y = np.tile(y, (2, 1))
    y = y + noise * y.std(0) * rng.standard_normal(y.shape)
    return PeriodSpectra.from_signals([np.tile(u, 2)[:, None]], [y], period=PERIOD, fs=FS), sensors


@pytest.mark.parametrize("element, place", [
    (DeadZoneSpring(2e5, 2e-4), ("middle", "tip")),
    (CoulombFriction(20.0, 1e-3), ("base", "middle")),
    (CubicStiffness(5e10), ("tip", None)),
    (DeadZoneSpring(2e5, 2e-4), ("middle", None)),
])
def test_the_force_s_points_are_read_from_the_content_above_the_band(element, place):
    sp, sensors = spectra([Connection(element, *place)])
    reading = read_entry(sp, sensors, TOP, PLACES)
    assert reading.place == place
    assert reading.snr_db > SNR_DB + 5
    # the direction is the force's through the masses (the mass line): one
    # point alone, or a pair's two points in the inverse ratio of their
    # masses and opposite in sign
    a = POINTS.index(place[0])
    if place[1] is None:
        assert abs(reading.direction[a]) > 0.95
    else:
        b = POINTS.index(place[1])
        assert reading.direction[a] / reading.direction[b] == pytest.approx(-M[b, b] / M[a, a], rel=0.2)
    assert "enters" in str(reading)


def test_a_linear_structure_gives_no_reading():
    sp, sensors = spectra([])
    reading = read_entry(sp, sensors, TOP, PLACES)
    assert reading.place is None and not reading.clear
    assert abs(reading.snr_db) < 1.0  # nothing but noise above the band
    assert "no place read" in str(reading)


def test_a_noise_free_linear_simulation_gives_no_reading():
    """Its content above the band is rounding, 1e-26 of the band's power:
    credited the locator's noise floor, it stands far below it."""
    sp, sensors = spectra([], noise=0.0)
    reading = read_entry(sp, sensors, TOP, PLACES)
    assert reading.place is None and reading.snr_db < -100
    sp, sensors = spectra([Connection(DeadZoneSpring(2e5, 2e-4), "middle", "tip")], noise=0.0)
    assert read_entry(sp, sensors, TOP, PLACES).place == ("middle", "tip")


def test_displacement_sensors_read_as_accelerations():
    """The same pair from displacements (less noise: a displacement sensor
    sees the content above the band 40 dB smaller against its own rms)."""
    place = ("middle", "tip")
    sp, sensors = spectra([Connection(DeadZoneSpring(2e5, 2e-4), *place)], kind="displacement", noise=1e-3)
    reading = read_entry(sp, sensors, TOP, PLACES)
    assert reading.place == place
    assert reading.direction[1] / reading.direction[2] == pytest.approx(-0.5, rel=0.2)


def test_only_candidate_places_are_read():
    """A pair the engineer rules out is not named; its points alone do not
    hold the direction (each a share below MIN_EXPLAINED)."""
    sp, sensors = spectra([Connection(DeadZoneSpring(2e5, 2e-4), "middle", "tip")])
    reading = read_entry(sp, sensors, TOP, [("base", "middle"), ("base", None), ("middle", None)])
    assert reading.place is None
    assert max(reading.explained.values()) < 0.9


def test_two_sensors_at_one_point_give_no_reading():
    sp, _ = spectra([Connection(DeadZoneSpring(2e5, 2e-4), "middle", "tip")])
    sensors = [("base", "acceleration"), ("tip", "acceleration"), ("tip", "displacement")]
    assert read_entry(sp, sensors, TOP, PLACES).place is None


@pytest.mark.skipif(not F16.exists(), reason="F-16 data not in ../shared/data/f16")
def test_f16_impacts_enter_at_the_payload():
    """The F-16's estimation levels: the content above 15 Hz is the
    payload's, 18 dB over the noise; the wing and drive sensors do not move
    against it (so its other side is not read: the ground or a heavier
    part). Levels 1 and 3 alone (no knocks): their content there points at
    no place."""
    from sklearn_pnlss.datasets import load_f16

    sensors = [(p, "acceleration") for p in ("drive", "wing", "payload")]
    places = [*combinations(["drive", "wing", "payload"], 2), *((p, None) for p in ("drive", "wing", "payload"))]
    records = {level: load_f16(F16, level=level, validation_level=None) for level in (1, 3, 5, 7)}

    def read(levels):
        sp = PeriodSpectra.from_signals([records[k].X[0] for k in levels], [records[k].y[0] for k in levels],
                                        period=8192, fs=400.0)
        return read_entry(sp, sensors, 15.0, places)

    reading = read((1, 3, 5, 7))
    assert reading.place == ("payload", None)
    assert reading.record == 3  # level 7
    assert 15.0 < reading.snr_db < 21.0
    assert reading.direction[2] > 0.95
    assert reading.explained[("wing", "payload")] - reading.explained[("payload", None)] < 0.02
    assert read((1, 3)).place is None
