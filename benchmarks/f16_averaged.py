"""The F-16 ground vibration test by the benchmark's protocol, with the
decoupled model averaged over its random starts (``AveragedRegressor``),
free and stable at rest (issue 35).

    python benchmarks/f16_averaged.py [--members 5] [--data-dir DIR] [--output FILE]

The model is ``bench_f16.py``'s best: ``DecoupledPNLSSRegressor(18,
n_branches=3, degree=5, branch_basis="signed_powers", init="random",
n_init=2)`` from the BLA of 18 states, with its response above the band
(``AboveBandRegressor``, the gated filters). For ``stable_at_rest`` False
and True, ``AveragedRegressor`` of that model with ``--members`` members
(``random_state=0``: member ``i`` fitted with ``random_state=i``, the
draws of ``bench_f16.py``'s ``@i``) is fitted on the estimation levels
(the BLA is deterministic: fitted once, every member starts from it).
The rows:

- ``averages``: the mean of the first ``k`` members, ``k = 1 ..
  members``. It is the model ``AveragedRegressor(n_estimators=k,
  random_state=0)`` fits, as member ``i``'s seed is ``i`` whatever the
  count; its fit time is the BLA's plus those members' own (timed one by
  one), and its radius at rest its members' largest (their parallel
  connection has all their poles).
- ``members``: each member alone.

Each row holds the test levels' NRMSE in periodic steady state (the
benchmark's figure), split over frequency, from rest as the official
loader scores it, and the test levels' sine sweeps simulated from rest (a
waveform the fit never saw: where the members' errors are least alike).
Writes ``results/f16_averaged.json``; its ``best`` is the row of the
lowest mean test NRMSE among the averages fitted in under 10 minutes.
"""
import argparse
import copy
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402

STATES, BRANCHES, DEGREE, BASIS = 18, 3, 5, "signed_powers"


def first_members(averaged, k):
    """The fitted ``AveragedRegressor`` of the first ``k`` members of
    ``averaged``: what ``n_estimators=k`` with the same integer
    ``random_state`` fits, since member ``i``'s seed does not depend on
    the count."""
    subset = copy.copy(averaged)
    subset.n_estimators = k
    subset.estimators_, subset.seeds_ = averaged.estimators_[:k], averaged.seeds_[:k]
    subset.n_params_ = sum(member.n_params_ for member in subset.estimators_)
    return subset


def timed_members(fit_times):
    """Wrap the library's member fit so that each member's time lands in
    ``fit_times`` (seed -> seconds); returns the function to restore."""
    from sklearn_pnlss.estimators import averaged

    original = averaged._fit_member

    def timed(regressor, seed, X, y, fit_params):
        t0 = time.perf_counter()
        member = original(regressor, seed, X, y, fit_params)
        fit_times[seed] = time.perf_counter() - t0
        return member

    averaged._fit_member = timed
    return lambda: setattr(averaged, "_fit_member", original)


def fit_averaged(start, start_s, X, y, test, n_members, stable_at_rest):
    """The rows of the averages of the first k members and of each member."""
    from sklearn_pnlss import AboveBandRegressor, AveragedRegressor

    decoupled = bench_f16.decoupled_estimator(STATES, BRANCHES, DEGREE, branch_basis=BASIS).set_params(
        stable_at_rest=stable_at_rest)
    model = AveragedRegressor(AboveBandRegressor(decoupled, cutoff=bench_f16.BAND_EDGES[1], fs=400.0),
                              n_estimators=n_members, random_state=0)
    fit_times = {}
    restore = timed_members(fit_times)
    try:
        model.fit(start.transform(X), y)
    finally:
        restore()
    inside = f"DecoupledPNLSSRegressor({STATES}, {BRANCHES}, {DEGREE}, {BASIS}) random" + (
        ", stable_at_rest" if stable_at_rest else "")
    settings = {"estimator_inside": inside, "n_states": STATES, "n_branches": BRANCHES, "degree": DEGREE,
                "branch_basis": BASIS, "init": "random", "n_init": decoupled.n_init, "max_iter": decoupled.max_iter,
                "stable_at_rest": stable_at_rest, "cutoff_hz": bench_f16.BAND_EDGES[1]}
    averages, members = [], []
    for k in range(1, n_members + 1):
        subset = first_members(model, k)
        fit_s = start_s + sum(fit_times[int(seed)] for seed in subset.seeds_)
        averages.append(bench_f16.entry(f"AveragedRegressor(AboveBandRegressor({inside}), n_estimators={k})",
                                        {**settings, "n_estimators": k, "random_state": 0}, subset, test, fit_s))
    for seed, member in zip(model.seeds_, model.estimators_):
        members.append(bench_f16.entry(f"AboveBandRegressor({inside}), random_state={seed}",
                                       {**settings, "random_state": int(seed)}, member, test,
                                       start_s + fit_times[int(seed)]))
    return averages, members


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--members", type=int, default=5)
    parser.add_argument("--output", default=RESULTS / "f16_averaged.json")
    args = parser.parse_args(argv)

    from sklearn_pnlss import BLAEstimator
    from sklearn_pnlss.datasets import load_f16

    X, y, test = bench_f16.load(args.data_dir)
    bench_f16.TEST_SWEEPS.update({lv: load_f16(args.data_dir, level=lv, kind="sinesweep", validation_level=None)
                                  for lv in bench_f16.TEST_LEVELS})
    t0 = time.perf_counter()
    start = BLAEstimator(STATES, period=8192, fs=400.0).fit(X, y)
    start_s = time.perf_counter() - t0
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "published": bench_f16.PUBLISHED, "start_s": start_s, "runs": []}
    for stable_at_rest in (False, True):
        print(f"stable_at_rest={stable_at_rest}: {args.members} members", flush=True)
        averages, members = fit_averaged(start, start_s, X, y, test, args.members, stable_at_rest)
        results["runs"].append({"stable_at_rest": stable_at_rest, "averages": averages, "members": members})
        write_results(results, args.output)
    results["best"] = bench_f16.best_within_budget([row for run in results["runs"] for row in run["averages"]])
    write_results(results, args.output)


if __name__ == "__main__":
    main()
