"""Where in a structure the simulator is wrong (ConnectionLocator): a chain
with one nonlinear connection, the right pair of masses and force law found
from three accelerometers, with the exact nominal and with one read off the
lowest level; no place claimed on a linear structure; the F-16's levels."""
import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

from sklearn_pnlss.datasets import load_f16
from sklearn_pnlss.gap import ConnectionLocator, modal_nominal
from sklearn_pnlss.gap.connections.spectra import PeriodSpectra
from sklearn_pnlss.physics import BoucWen, Connection, CoulombFriction, CubicStiffness, DeadZoneSpring, Structure

POINTS = ["base", "middle", "tip"]
M = np.diag([3.0, 2.0, 1.0])
K = 5e4 * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
C = 1e-4 * K + 0.5 * M
SENSORS = [(p, "acceleration") for p in POINTS]
FS, PERIOD = 200.0, 4096


def _records(element, levels, noise=1e-3, seed=0, place=("middle", "tip")):
    """Three periods of a multisine 1-83 Hz at the base per level (a new
    realisation each), accelerations of the three masses integrated at 20
    times the data rate, white noise of ``noise`` times each channel's rms."""
    rng = np.random.default_rng(seed)
    connections = [] if element is None else [Connection(element, *place)]
    truth = Structure(M, C, K, points=POINTS, connections=connections)
    lines = np.arange(20, 1700, 4)
    X, Y = [], []
    for level in levels:
        spectrum = np.zeros(PERIOD // 2 + 1, complex)
        spectrum[lines] = np.exp(2j * np.pi * rng.random(lines.size))
        u = np.fft.irfft(spectrum, PERIOD)
        u *= level / u.std()
        a = truth.simulate(u, fs=FS, inputs="base", sensors=SENSORS, periodic=True, oversampling=20,
                           decimation=(4, 5))
        a = np.tile(a, (3, 1))
        X.append(np.tile(u, 3)[:, None])
        Y.append(a + noise * a.std(0) * rng.standard_normal(a.shape))
    return X, Y


def _locator(nominal=None):
    nominal = Structure(M, C, K, points=POINTS) if nominal is None else nominal
    return ConnectionLocator(nominal, fs=FS, period=PERIOD, inputs=["base"], sensors=SENSORS)


@pytest.mark.parametrize("element, law, coefficient, truth", [
    (CubicStiffness(3e8), "cubic_stiffness", "k3", 3e8),
    (DeadZoneSpring(3e4, 1e-3), "backlash", "kb", 3e4),
    (CoulombFriction(2.0, 1e-3), "coulomb_friction", "fc", 2.0),
])
def test_the_connection_and_its_law_are_found_on_a_chain(element, law, coefficient, truth):
    """The effect between the middle mass and the tip, three levels: the
    right place and law explain the nominal's error to the noise on the
    training levels and on two new ones, the coefficient within 10 %
    (a backlash's clearance is profiled on a grid of rms multiples, which
    its stiffness absorbs); the modal corrections fitted with every law
    explain the integration's linear error everywhere, and beyond them
    the right place's law gains twice what any other place's does."""
    X, Y = _records(element, (20.0, 40.0, 60.0))
    loc = _locator().fit(X, Y)
    best = loc.best_
    assert (best.place, best.law.name) == (("middle", "tip"), law)
    assert best.explained > 0.98 and best.nonlinear_gain > 0.1
    assert abs(best.parameters[coefficient] / truth - 1) < 0.1
    assert loc.ranking_[1].explained < best.explained - 0.05
    assert best.nonlinear_gain > 2 * max(c.nonlinear_gain for c in loc.ranking_[1:])
    X_val, Y_val = _records(element, (30.0, 50.0), seed=1)
    assert loc.score(X_val, Y_val) > 0.95


def test_a_joint_that_sticks_and_slips_is_found_as_a_hysteresis():
    """A Jenkins-like joint between the middle mass and the tip (stuck
    stiffness 2e4 N/m, slipping at 20 N): the locator's hysteresis law,
    read along the measured relative motion, explains the error to the
    noise at the right place on the training and on two new levels, its
    stuck stiffness within 10 % (its slip is profiled on a grid, which the
    stiffness absorbs in part); a backlash or a dry friction there explains
    less."""
    X, Y = _records(BoucWen(2e4, 1e3, 0.5, 0.5, 1.0), (20.0, 40.0, 60.0))
    loc = _locator().fit(X, Y)
    best = loc.best_
    assert (best.place, best.law.name) == (("middle", "tip"), "hysteresis")
    assert best.explained > 0.98
    assert abs(best.parameters["alpha"] / 2e4 - 1) < 0.1
    others = [c for c in loc.candidates_ if c.place == best.place and c.law.name != "hysteresis"]
    assert max(c.explained for c in others) < best.explained - 0.02
    X_val, Y_val = _records(BoucWen(2e4, 1e3, 0.5, 0.5, 1.0), (30.0, 50.0), seed=1)
    assert loc.score(X_val, Y_val) > 0.95


def test_a_nominal_read_off_the_lowest_level_finds_the_cubic_spring():
    """No model at all: the nominal is the modal model of the lowest level
    (5 N, where the spring barely acts); the cubic spring between the middle
    mass and the tip is found from the three higher levels, k3 within 5 %."""
    X, Y = _records(CubicStiffness(3e8), (5.0, 20.0, 40.0, 60.0), noise=1e-2)
    nominal = modal_nominal(X[0], Y[0], fs=FS, points=POINTS, driving_point="base", period=PERIOD,
                            f_band=(1.0, 80.0))
    assert nominal.modal_fit_.frequencies.size == 3
    loc = _locator(nominal).fit(X[1:], Y[1:])
    assert (loc.best_.place, loc.best_.law.name) == (("middle", "tip"), "cubic_stiffness")
    assert loc.best_.explained > 0.97
    assert abs(loc.best_.parameters["k3"] / 3e8 - 1) < 0.05


def test_a_linear_structure_leaves_only_noise_to_explain():
    """No effect: the nominal's error is the integrator's own (2 % of the
    output in the band at 20 times the data rate), linear: the modal
    corrections explain it as well as any law does (a real effect's law
    gains 10 % and more beyond them, above); without them a backlash
    profiled over its clearance picks up 1-2 % of it, a hysteresis (a
    loop that barely bends, a damping linear in the amplitude) 3 %."""
    X, Y = _records(None, (20.0, 60.0))
    loc = _locator().fit(X, Y)
    assert np.all(loc.nominal_error_ < 0.025)
    assert max(c.nonlinear_gain for c in loc.ranking_) < 1e-3
    plain = ConnectionLocator(Structure(M, C, K, points=POINTS), fs=FS, period=PERIOD, inputs=["base"],
                              sensors=SENSORS, linear_corrections=False).fit(X, Y)
    assert max(c.nonlinear_gain for c in plain.ranking_) < 0.04
    # a hysteresis is passive: its stuck stiffness is never read negative
    loops = [c for c in loc.candidates_ + plain.candidates_ if c.law.name == "hysteresis"]
    assert len(loops) == 12 and all(c.parameters["alpha"] >= 0 for c in loops)


@pytest.mark.parametrize("element, low, high", [(None, -1.0, 1.0), (DeadZoneSpring(3e4, 1e-3), -1.0, 10.0)])
def test_the_noise_of_one_period_is_read_at_the_lines_the_input_leaves_free(element, low, high):
    """One steady-state period per record (the chain's multisine excites
    every fourth line): the noise read at the free lines is the spread of
    three periods' to within 1 dB on a linear chain, and an upper bound
    (within 10 dB) with a backlash, whose content lies on those lines too."""
    X, Y = _records(element, (20.0, 40.0, 60.0))
    three = PeriodSpectra.from_signals(X, Y, period=PERIOD, fs=FS)
    one = PeriodSpectra.from_signals([x[:PERIOD] for x in X], [y[:PERIOD] for y in Y], period=PERIOD, fs=FS)
    assert np.all(three.n_periods == 3) and np.all(one.n_periods == 1)
    band = (three.freqs >= 1.0) & (three.freqs <= 83.0)
    ratio_db = 10 * np.log10(one.Y_noise[:, band].mean(axis=1) / (3 * three.Y_noise[:, band].mean(axis=1)))
    assert np.all(ratio_db > low) and np.all(ratio_db < high)


def test_bad_input_is_named():
    X, Y = _records(None, (20.0,))
    with pytest.raises(ValueError, match="which no sensor measures"):
        ConnectionLocator(Structure(M, C, K, points=POINTS), fs=FS, period=PERIOD, inputs=["base"],
                          sensors=SENSORS[:2], places=[("base", "tip")]).fit(X, [y[:, :2] for y in Y])
    full = np.fft.irfft(np.exp(2j * np.pi * np.random.default_rng(0).random(PERIOD // 2 + 1)), PERIOD)[:, None]
    with pytest.raises(ValueError, match="one period whose input excites nearly every line"):
        _locator().fit([full], [y[:PERIOD] for y in Y[:1]])
    with pytest.raises(ValueError, match="holds no steady-state period after transient_periods=1"):
        ConnectionLocator(Structure(M, C, K, points=POINTS), fs=FS, period=PERIOD, inputs=["base"], sensors=SENSORS,
                          transient_periods=1).fit([x[:PERIOD] for x in X], [y[:PERIOD] for y in Y])
    with pytest.raises(ValueError, match="one \\(point, kind\\) per column"):
        _locator().fit(X, [y[:, :2] for y in Y])
    with pytest.raises(ValueError, match="not a whole number of periods"):
        _locator().fit([x[:-3] for x in X], [y[:-3] for y in Y])


F16_SENSORS = [(p, "acceleration") for p in ("drive", "wing", "payload")]


@pytest.fixture(scope="module")
def f16(f16_dir):
    """The F-16's training levels 1, 3, 5, 7 and validation levels 2, 4, 6
    (records as lists), and the modal nominal read off level 1 in 2-15 Hz."""
    data = {level: load_f16(f16_dir, level=level, validation_level=None) for level in range(1, 8)}
    nominal = modal_nominal(data[1].X, data[1].y, fs=400.0, points=[p for p, _ in F16_SENSORS],
                            driving_point="drive", period=8192, f_band=(2.0, 15.0))
    train = [data[k].X[0] for k in (1, 3, 5, 7)], [data[k].y[0] for k in (1, 3, 5, 7)]
    test = [data[k].X[0] for k in (2, 4, 6)], [data[k].y[0] for k in (2, 4, 6)]
    return train, test, nominal


def test_the_f16s_gap_lies_at_the_wing_in_a_joint_that_sticks_and_slips(f16):
    """The F-16 (real data), nominal read off level 1 in 2-15 Hz, trained on
    levels 1, 3, 5, 7: the connection that explains most of the nominal's
    error acts at the wing sensor (to the ground, as these three sensors
    resolve it) and is a joint that sticks and slips: a Jenkins-like
    hysteresis (the loop unloading along its stuck stiffness) whose stuck
    stiffness the law's own stiffness change cancels within 10 %, so that
    the lowest level's nominal stays as it was and the wing softens and
    dissipates as it slips; 5 % and more beyond a linear change there with
    the modal corrections. With its coefficients fixed it explains at least
    95 % of the error on validation levels 4 and 6 and 80 % on level 2.
    A law between the wing and the payload gains less than half as much,
    though their relative motion is measured (above 20 dB of its noise at 77-86 % of the band's lines):
    a nominal read from one shaker position knows the interface only
    through the global modes, not its own flexibility (see the guide)."""
    train, test, nominal = f16
    loc = ConnectionLocator(nominal, fs=400.0, period=8192, inputs=["drive"], sensors=F16_SENSORS,
                            f_band=(2.0, 15.0))
    loc.fit(*train)
    best = loc.best_
    assert best.place == ("wing", None) and best.law.name == "hysteresis"
    p = best.parameters
    assert p["gamma"] == p["delta"] and abs(p["stiffness"] / p["alpha"] + 1) < 0.1
    assert best.explained > 0.95 and best.nonlinear_gain > 0.05
    nominal_error, explained = loc.explained(*test)
    assert np.all(nominal_error[1:] > 1.0) and np.all(explained[1:] > 0.95) and explained[0] > 0.8
    pair = next(c for c in loc.ranking_ if c.place == ("wing", "payload"))
    assert pair.nonlinear_gain < 0.5 * best.nonlinear_gain


def test_the_f16s_level_dependence_fits_no_sensor_places_shape(f16_dir):
    """Why the place stops at the wing (``benchmarks/f16_softening.py``):
    from level 1 to level 7 each mode loses stiffness and gains damping in
    proportion to the square of its share of the joint's motion, whatever
    the joint's law. No place of the three sensors has that shape: the best
    (a point to the ground) explains under 70 % of the modes' stiffness
    loss, the wing-payload interface under 40 % of it and under 25 % of
    the damping gain, the least of all. The 6.6 Hz mode loses the most
    stiffness, and every sensor sees it the least: the joint's motion in
    it is not at these sensors."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    pattern = importlib.import_module("f16_softening").softening_pattern(f16_dir)
    shares = {tuple(r["place"]): (r["stiffness_explained"], r["damping_explained"]) for r in pattern["places"]}
    assert max(s for s, _ in shares.values()) < 0.7
    assert shares[("wing", "payload")][0] < 0.4 and shares[("wing", "payload")][1] < 0.25
    assert min(shares, key=lambda place: shares[place][0]) == ("wing", "payload")
    assert np.argmax(pattern["stiffness_loss"]) == 3 and round(pattern["frequencies_hz"][3], 1) == 6.6
    assert all(np.argmin(np.abs(shape)) == 3 for shape in pattern["shapes"].values())


def _docstring_records():
    """The records of ConnectionLocator's example: two periods of a
    multisine 0.5-41.5 Hz at two levels, 0.1 % noise."""
    truth = Structure(M, C, K, points=POINTS, connections=[Connection(CubicStiffness(3e8), "middle", "tip")])
    rng = np.random.default_rng(0)
    spectrum = np.zeros(2049, complex)
    spectrum[10:850:2] = np.exp(2j * np.pi * rng.random(420))
    u = np.fft.irfft(spectrum)
    X, Y = [], []
    for level in (20.0, 60.0):
        a = truth.simulate(level * u / u.std(), fs=FS, inputs="base", sensors=SENSORS, periodic=True,
                           oversampling=20, decimation=(4, 5))
        X.append(np.tile(level * u / u.std(), 2)[:, None])
        Y.append(np.tile(a, (2, 1)) * (1 + 1e-3 * rng.standard_normal((8192, 3))))
    return X, Y


@pytest.mark.parametrize("motion_snr", [100.0, 10.0])
def test_a_free_participation_places_a_chains_spring(motion_snr):
    """participation="free" fits the connection's share of every mass with
    the law: on the chain (exact nominal, 0.1 % noise) it places the cubic
    spring right, as the nominal's shapes do, with the relative motion read
    20 dB or 10 dB over its noise."""
    X, Y = _records(CubicStiffness(3e8), (20.0, 60.0))
    loc = ConnectionLocator(Structure(M, C, K, points=POINTS), fs=FS, period=PERIOD, inputs=["base"],
                            sensors=SENSORS, participation="free", motion_snr=motion_snr).fit(X, Y)
    assert loc.best_.place == ("middle", "tip") and loc.best_.law.name == "cubic_stiffness"
    assert loc.best_.explained > 0.99 and loc.best_.participation.shape == (3,)
    assert loc.best_.corrections is None


def test_a_free_participation_read_down_to_10_db_can_misplace():
    """The limit of that reading: on the example's shorter records (two
    periods of a narrower multisine) the lines between 10 and 20 dB bias the
    law enough that another pair leads (a backlash from the base to the
    tip), where at 20 dB the spring is found. The F-16's answer below needs
    10 dB: a clue to check, not a verdict."""
    X, Y = _docstring_records()
    kwargs = dict(fs=FS, period=PERIOD, inputs=["base"], sensors=SENSORS, participation="free")
    assert ConnectionLocator(Structure(M, C, K, points=POINTS), **kwargs).fit(X, Y).best_.place == ("middle", "tip")
    noisy = ConnectionLocator(Structure(M, C, K, points=POINTS), motion_snr=10.0, **kwargs).fit(X, Y)
    assert noisy.best_.place == ("base", "tip")


def test_the_f16s_wing_payload_motion_explains_most_with_a_free_participation(f16):
    """The F-16 as above, each mode's share of the connection fitted
    (participation="free") and the relative motions read down to 10 dB
    over their noise: the wing-payload interface, which the benchmark's
    description names, explains the most (97 %), and with its coefficients
    fixed 75 % and more of the error on validation level 2 and 95 % on
    levels 4 and 6. Its lead is narrow: a hysteresis from the wing or the
    payload to the ground explains 95 % and 94 %, and no more than 80 % of
    level 2 either (without that law no other place explained 35 % there).
    Its share of each mode differs from the nominal's phi_wing - phi_payload
    in sign on two modes (4.0 and 6.6 Hz) and by a factor of 2.5 and more
    on five: the nominal's shapes at the interface are what hid it. At the
    default 20 dB the same place explains the least."""
    train, test, nominal = f16
    kwargs = dict(fs=400.0, period=8192, inputs=["drive"], sensors=F16_SENSORS, f_band=(2.0, 15.0),
                  participation="free")
    loc = ConnectionLocator(nominal, motion_snr=10.0, **kwargs).fit(*train)
    best = loc.best_
    assert best.place == ("wing", "payload") and best.explained > 0.96
    explained = {c.place: loc.explained(*test, c)[1] for c in loc.ranking_}
    assert explained[best.place][0] > 0.75 and np.all(explained[best.place][1:] > 0.95)
    assert loc.ranking_[1].explained < best.explained - 0.01
    assert all(e[0] < 0.8 for place, e in explained.items() if place != best.place)
    own = nominal.direction("wing", "payload")[nominal.coupled]
    ratio = best.participation / own
    assert np.sum(ratio < 0) == 2 and np.sum(np.abs(ratio) > 2.5) >= 5
    at_20_db = ConnectionLocator(nominal, **kwargs).fit(*train)
    assert at_20_db.ranking_[-1].place == ("wing", "payload")
