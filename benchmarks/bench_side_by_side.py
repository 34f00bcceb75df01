"""Two fits side by side in one process, as ``AveragedRegressor(n_jobs=2)``
runs its members: the F-16 model of the band of ``f16_lru.py`` (issue 35).

    python benchmarks/bench_side_by_side.py [--data-dir DIR] [--output FILE]

Two members of ``DecoupledPNLSSRegressor(18, n_branches=3, degree=5,
branch_basis="signed_powers", init="random", n_init=1)`` (525 parameters,
50 iterations) fitted at a time in joblib threads from the BLA of 18
states, on the estimation multisines (four levels, each its periods'
mean: 98304 residuals), three ways:

- ``blas_in_each``: BLAS as configured (two threads) in each fit, as the
  library ran them before: two fits' Gram matrices contend for two cores;
- ``one_blas_thread``: BLAS on one thread while both run (each fit a
  core), in double precision throughout;
- ``single_precision``: the same, the Jacobian blocks and their Gram
  matrix in single precision (the library's rule from 512 parameters).

Each way: the fit time and the test multisines' mean NRMSE of the mean of
the two members (periodic steady state), to show the models are the same.
Writes ``results/side_by_side.json``.
"""
import argparse
import sys
import time
from contextlib import nullcontext
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402


def fit_two(X_start, y, way):
    """The two members fitted side by side ``way``; (model, seconds)."""
    from sklearn_pnlss import AveragedRegressor
    from sklearn_pnlss.estimators import averaged
    from sklearn_pnlss.statespace import objective
    from sklearn_pnlss.utils.threads import side_by_side_blas

    member = bench_f16.decoupled_estimator(18, 3, 5, branch_basis="signed_powers", n_init=1).set_params(n_jobs=1)
    model = AveragedRegressor(member, n_estimators=2, n_jobs=2, random_state=0)
    rule = objective.SINGLE_PRECISION_PARAMS
    if way != "single_precision":
        objective.SINGLE_PRECISION_PARAMS = 10**9
    if way == "blas_in_each":  # the library before: no BLAS limit around the members' threads
        averaged.side_by_side_blas = lambda n_jobs, n_tasks: nullcontext()
    try:
        t0 = time.perf_counter()
        model.fit(X_start, y)
        return model, time.perf_counter() - t0
    finally:
        objective.SINGLE_PRECISION_PARAMS = rule
        averaged.side_by_side_blas = side_by_side_blas


def main(argv=None):
    import warnings

    from sklearn_pnlss import BLAEstimator

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--output", default=RESULTS / "side_by_side.json")
    args = parser.parse_args(argv)

    X, y, test = bench_f16.load(args.data_dir)
    start = BLAEstimator(18, period=8192, fs=400.0).fit(X, y)
    results = {**header(), "model": "2 x DecoupledPNLSSRegressor(18, 3, 5, signed_powers, n_init=1, max_iter=50)",
               "ways": {}}
    for way in ("blas_in_each", "one_blas_thread", "single_precision"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the members' stability warnings: f16_lru.py reports them
            model, seconds = fit_two(start.transform(X), y, way)
        _, mean, _ = bench_f16.nrmse(model, test)
        results["ways"][way] = {"fit_s": seconds, "mean_nrmse": mean,
                                "n_params": [int(m.n_params_) for m in model.estimators_]}
        print(f"{way:18s} fit {seconds:6.1f} s  test mean NRMSE {mean:.4f}", flush=True)
        write_results(results, args.output)


if __name__ == "__main__":
    main()
