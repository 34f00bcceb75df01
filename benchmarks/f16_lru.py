"""The F-16's response above its excited band learned by a deep network of
linear recurrent units (``LRUAboveBandRegressor``), trained on the
estimation levels' multisines and sine sweeps (issue 35).

    python benchmarks/f16_lru.py [--draws 0 1] [--data-dir DIR] [--output FILE]

For each draw of the random starts, ``bench_f16.py``'s best model of the
band (``DecoupledPNLSSRegressor(18, n_branches=3, degree=5,
branch_basis="signed_powers", init="random")`` from the BLA of 18 states,
fitted on the multisines of levels 1, 3, 5 and 7) is kept as it is
(``FrozenEstimator``) and given its response above 15.5 Hz by
``LRUAboveBandRegressor`` at its defaults (three layers of 64 recursions,
32 channels, 300 Adam iterations; ``random_state`` the draw's): it reads
the force, the force's content above the band and the model's simulation,
and is fitted on the multisines (each its periods' mean, in steady state)
and the estimation levels' sine sweeps (segments from rest). Nothing was
chosen on the test levels: the settings are the class's defaults, set
before any F-16 run of the numpy implementation.

Each row holds the test multisines' NRMSE (periodic steady state), the test
levels' sine sweeps (from rest), the fit time (the BLA's, the model's and
the network's) and the parameter counts; then the mean of the draws'
models. Writes ``results/f16_lru.json``; its ``best`` is the row of lowest
mean test NRMSE fitted in under ten minutes.
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402
from f16_clearances import (BASIS, BRANCHES, DEGREE, STATES, MeanOfMembers, load_and_start,  # noqa: E402
                            map_signals)


def draw_rows(seed, start, start_s, X, y, train_sweeps, test):
    """The rows of one draw (the model of the band alone, then with the
    network above it) and the network's model with its own fit time."""
    from sklearn.frozen import FrozenEstimator

    from sklearn_pnlss import LRUAboveBandRegressor

    decoupled = bench_f16.decoupled_estimator(STATES, BRANCHES, DEGREE, branch_basis=BASIS, random_state=seed)
    t0 = time.perf_counter()
    decoupled.fit(start.transform(X), y)
    model_s = time.perf_counter() - t0
    inside = f"DecoupledPNLSSRegressor({STATES}, {BRANCHES}, {DEGREE}, {BASIS}) random, random_state={seed}"
    settings = {"n_states": STATES, "n_branches": BRANCHES, "degree": DEGREE, "branch_basis": BASIS,
                "random_state": seed}
    rows = [bench_f16.entry(inside, settings, decoupled, test, start_s + model_s)]
    t0 = time.perf_counter()
    network = LRUAboveBandRegressor(FrozenEstimator(decoupled), cutoff=bench_f16.BAND_EDGES[1], fs=400.0,
                                    random_state=seed).fit(*map_signals(X, y, train_sweeps, True))
    network_s = time.perf_counter() - t0
    params = network.get_params(deep=False)
    named = {k: params[k] for k in ("width", "n_layers", "n_modes", "max_iter", "learning_rate", "segment_length",
                                    "burn_in")}
    extra = {"n_above_band_params": int(network.n_map_params_), "network_fit_s": network_s,
             "above_band_explained_train": network.explained_fraction_.tolist(),
             "loss_first_last": [float(network.loss_curve_[0]), float(network.loss_curve_[-1])]}
    rows.append(bench_f16.entry(f"LRUAboveBandRegressor({inside})",
                                {**settings, "cutoff_hz": network.cutoff, "train_sweeps": True, **named},
                                network, test, start_s + model_s + network_s, extra))
    return rows, (network, model_s + network_s)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--output", default=RESULTS / "f16_lru.json")
    args = parser.parse_args(argv)

    X, y, test, train_sweeps, start, start_s = load_and_start(args.data_dir)
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "published": bench_f16.PUBLISHED, "start_s": start_s, "draws": [], "averages": []}
    members = {}
    for seed in args.draws:
        print(f"draw {seed}", flush=True)
        rows, members[seed] = draw_rows(seed, start, start_s, X, y, train_sweeps, test)
        results["draws"].append({"random_state": seed, "rows": rows})
        write_results(results, args.output)
    seeds = list(members)
    for k in range(2, len(seeds) + 1):
        chosen = seeds[:k]
        results["averages"].append(bench_f16.entry(
            f"mean of draws {chosen}: LRUAboveBandRegressor", {"draws": chosen},
            MeanOfMembers([members[s][0] for s in chosen]), test, start_s + sum(members[s][1] for s in chosen)))
    results["best"] = bench_f16.best_within_budget([row for d in results["draws"] for row in d["rows"]]
                                                   + results["averages"])
    write_results(results, args.output)


if __name__ == "__main__":
    main()
