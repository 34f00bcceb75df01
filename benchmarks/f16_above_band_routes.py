"""What could predict the F-16's response above its excited band, measured
on the data alone, with no model (issue 35).

The test levels' NRMSE target (0.13 in the mean) lies below what a model
whose response ends at the band's edge reaches even if it were exact inside
it (``out_of_band_floor`` in ``results/f16.json``: 0.132). Each route below
is a causal FIR map (200 taps) onto the outputs' content above 15.5 Hz,
fitted by ridge regression on the estimation levels 1, 3, 5, 7 (each
record's averaged period) and applied to the test levels 2, 4, 6, from
inputs a model could at best know exactly:

- ``force``: the measured force's content above the band (a linear map);
- ``force, gated by the response's envelope``: the same switched on by the
  measured amplitude envelope of the outputs' content above the band, the
  gate ``AboveBandRegressor`` predicts from the model's state, here taken
  from the measurement (its best case);
- ``in-band motion``: clearance hinges, friction signs, cubes and the
  motion itself of the measured in-band displacements and velocities at
  each sensor and between each pair (what a map of the simulated in-band
  motion would see if the simulation were exact).

For each: the share of each test level's power above the band it explains,
per output (averaged period), and the NRMSE of the test records (all eight
periods) when the in-band part is exact (the measured averaged period's)
and the route adds its prediction. Writes
``results/f16_above_band_routes.json``.

    python benchmarks/f16_above_band_routes.py [--data PATH]
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402
from bench_f16 import nrmse_of  # noqa: E402

from sklearn_pnlss.datasets import load_f16  # noqa: E402
from sklearn_pnlss.estimators._gated import above_cutoff, apply_fir, envelope, fit_fir  # noqa: E402

PERIOD, FS, CUTOFF = 8192, 400.0, 15.5
TRAIN_LEVELS, TEST_LEVELS = (1, 3, 5, 7), (2, 4, 6)
N_TAPS, ALPHA = 200, 1e-4
ENVELOPE_WINDOW = 50  # samples (125 ms) over which the gate's envelope is averaged
CLEARANCES = (0.5, 1.0, 1.5, 2.0)  # hinge knees, in rms of the highest estimation level's motion
PLACES = [(0, None), (1, None), (2, None), (2, 1), (2, 0), (1, 0)]  # sensor, or sensor pair (drive, wing, payload)
FORCE, GATED, MOTION = "force", "force, gated by the response's envelope", "in-band motion"
ROUTES = (FORCE, GATED, MOTION)


def averaged_period(signal):
    """The mean period of a (n_samples, n_channels) steady-state record."""
    return signal.reshape(-1, PERIOD, signal.shape[-1]).mean(axis=0)


def in_band(signal):
    """The content of each channel of one period at and below the cutoff
    (the mean removed)."""
    return signal - above_cutoff(signal, CUTOFF, FS) - signal.mean(axis=0)


def in_band_motion(acceleration):
    """Displacement and velocity of one period of acceleration, in the band
    (integrated on the DFT lines: no drift)."""
    spectrum = np.fft.rfft(in_band(acceleration), axis=0)
    s = 2j * np.pi * np.fft.rfftfreq(PERIOD, 1 / FS)
    s[0] = 1.0
    return (np.fft.irfft(spectrum / s[:, None] ** 2, PERIOD, axis=0),
            np.fft.irfft(spectrum / s[:, None], PERIOD, axis=0))


def relative(motion, place):
    a, b = place
    return motion[:, a] - (0.0 if b is None else motion[:, b])


def motion_features(acceleration, reference):
    """Joint-law features of the in-band motion at each place, displacement
    and velocity in units of ``reference`` (their rms at the highest level,
    so a clearance is one displacement at every level)."""
    d, v = in_band_motion(acceleration)
    columns = []
    for place, (d_ref, v_ref) in zip(PLACES, reference):
        dr, vr = relative(d, place) / d_ref, relative(v, place) / v_ref
        columns += [dr, vr, dr**3, vr * np.abs(vr), np.tanh(vr / 0.1)]
        columns += [hinge for c in CLEARANCES for hinge in (np.maximum(dr - c, 0.0), np.minimum(dr + c, 0.0))]
    return np.column_stack(columns)


def route_inputs(route, force, output, scale, reference):
    """The FIR inputs of ``route`` along one averaged period."""
    force_above = above_cutoff(force, CUTOFF, FS)
    if route == FORCE:
        return force_above
    if route == GATED:
        return force_above * envelope(above_cutoff(output, CUTOFF, FS), scale, ENVELOPE_WINDOW, True)[:, None]
    return motion_features(output, reference)


def routes(data_dir):
    train = [load_f16(data_dir, level=lv, validation_level=None) for lv in TRAIN_LEVELS]
    test = {lv: load_f16(data_dir, level=lv, validation_level=None) for lv in TEST_LEVELS}
    u_train = [averaged_period(d.X[0]) for d in train]
    y_train = [averaged_period(d.y[0]) for d in train]
    above_train = [above_cutoff(y, CUTOFF, FS) for y in y_train]
    scale = np.std(above_train[-1], axis=0)
    d_top, v_top = in_band_motion(y_train[-1])
    reference = [(np.std(relative(d_top, p)), np.std(relative(v_top, p))) for p in PLACES]
    # Each test level: its averaged period's force and output, and the output's content above the band.
    periods = {lv: (averaged_period(d.X[0]), averaged_period(d.y[0])) for lv, d in test.items()}
    above_test = {lv: above_cutoff(y, CUTOFF, FS) for lv, (_, y) in periods.items()}

    def nrmse(lv, above_predicted):
        """The test record's NRMSE with its in-band part exact and ``above_predicted`` above the band."""
        record = test[lv].y[0]
        period = periods[lv][1] - above_test[lv] + above_predicted
        return nrmse_of(np.tile(period, (record.shape[0] // PERIOD, 1)), record).tolist()

    rows = [{"route": "nothing above the band", "explained": None,
             "nrmse": {str(lv): nrmse(lv, 0.0) for lv in test}}]
    for route in ROUTES:
        inputs = [route_inputs(route, u, y, scale, reference) for u, y in zip(u_train, y_train)]
        column_scale = np.std(np.vstack(inputs), axis=0)
        column_scale[column_scale == 0] = 1.0
        fir = fit_fir([w / column_scale for w in inputs], above_train, [True] * len(inputs), N_TAPS, ALPHA)
        explained, per_level = {}, {}
        for lv, (u, y) in periods.items():
            above = above_test[lv]
            predicted = apply_fir(route_inputs(route, u, y, scale, reference) / column_scale, fir, True)
            explained[str(lv)] = (1 - np.sum((above - predicted) ** 2, axis=0) / np.sum(above**2, axis=0)).tolist()
            per_level[str(lv)] = nrmse(lv, predicted)
        rows.append({"route": route, "explained": explained, "nrmse": per_level})
    for row in rows:
        row["mean_nrmse"] = float(np.mean(list(row["nrmse"].values())))
    return {"cutoff_hz": CUTOFF, "n_taps": N_TAPS, "train_levels": list(TRAIN_LEVELS),
            "test_levels": list(TEST_LEVELS), "routes": rows}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "f16"))
    args = parser.parse_args(argv)
    result = routes(args.data)
    print(f"in-band part exact, test levels {TEST_LEVELS}; NRMSE per output (drive / wing / payload), and the share "
          f"of the power above {CUTOFF} Hz each route explains")
    for row in result["routes"]:
        print(f"  {row['route']:<42} mean {row['mean_nrmse']:.3f}  " + "  ".join(
            f"L{lv} " + "/".join(f"{v:.3f}" for v in row["nrmse"][str(lv)]) for lv in TEST_LEVELS))
        if row["explained"]:
            print(f"  {'':<42} explained " + "  ".join(
                f"L{lv} " + "/".join(f"{v:.2f}" for v in row["explained"][str(lv)]) for lv in TEST_LEVELS))
    write_results({**header(), **result}, RESULTS / "f16_above_band_routes.json")


if __name__ == "__main__":
    main()
