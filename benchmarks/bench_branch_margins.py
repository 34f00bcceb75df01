"""How far past its training range can a decoupled model's branches be trusted?

The main job's decoupled model (3 branches of degree 10, from the states and
input PNLSS (2, 3), ``python -m sklearn_pnlss`` with its defaults) is fitted
by the main job itself, then refitted from the same start on the same data
with each other treatment of a branch input outside its range:

* ``extrapolation="hold"`` with ``range_margin`` 0 (the default: the main
  job's model itself), 0.02 and 0.1 of the range's width;
* ``extrapolation="linear"`` (the edge tangent);
* ``extrapolation="polynomial"`` (the plain polynomial).

Each is scored on the main job's simulated test multisine (the training
level, 55 N rms, noiseless) and sweep. The user guide (``decoupling.rst``,
"Reading the branches") quotes these figures; ``tests/test_docs.py`` checks
the text against the results file.

    python benchmarks/bench_branch_margins.py [--n-jobs 2] [--output FILE]

About 2 minutes on 2 cores. Results go to
``benchmarks/results/branch_margins.json``.
"""
import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, score_test_signals, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "branch_margins.json"
VARIANTS = {
    # The main job's model refitted here: the path the variants take
    # reproduces the main job's fit.
    "hold_refitted": {},
    "hold_margin_0.02": {"range_margin": 0.02},
    "hold_margin_0.1": {"range_margin": 0.1},
    "linear": {"extrapolation": "linear"},
    "polynomial": {"extrapolation": "polynomial"},
}


def main(argv=None):
    from sklearn.base import clone

    from sklearn_pnlss.app.study import run_study
    from sklearn_pnlss.datasets import make_bouc_wen
    from sklearn_pnlss.persistence import load
    from sklearn_pnlss.utils.handover import attach_stage

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        summary = run_study(output_dir=tmp, models=("pnlss_si", "decoupled"), n_jobs=args.n_jobs,
                            save_models=True, plots=False, progress=False)
        main_seconds = time.perf_counter() - t0
        start, held = load(Path(tmp, "pnlss_si.joblib")), load(Path(tmp, "decoupled.joblib"))
    training = summary["training"]
    # The main job's data, as run_study draws them: the last realisation
    # is for validation (its last period).
    data = make_bouc_wen(n_realizations=training["n_realizations"] + 1, n_periods=training["n_periods"],
                         rms=training["rms_N"], noise_rms=training["noise_rms_m"],
                         random_state=training["random_state"], n_jobs=args.n_jobs)
    P = data.period
    X, y = data.X_train[:-1], data.y_train[:-1]
    X_val, y_val = data.X_train[-1:, -P:], data.y_train[-1:, -P:]

    row = next(r for r in summary["results"] if r["model"] == "decoupled")
    rows = [{"variant": "hold", "params": {}, "fit_s": row["fit_time_s"],
             "main_job": {"multisine": row["multisine_db"], "sweep": row["sweep_db"]},
             **score_test_signals(held, data)}]
    print(f"{'hold':<18}{rows[0]['multisine']:>9.2f}{rows[0]['sweep']:>9.2f}  (the main job's model)", flush=True)
    for name, params in VARIANTS.items():
        t0 = time.perf_counter()
        model = clone(held).set_params(**params).fit(attach_stage(X, start), y, X_val=X_val, y_val=y_val)
        scores = score_test_signals(model, data)
        rows.append({"variant": name, "params": params, "fit_s": round(time.perf_counter() - t0, 1), **scores})
        cells = "".join(f"{'diverged' if v is None else f'{v:.2f}':>9}" for v in scores.values())
        print(f"{name:<18}{cells}", flush=True)
    results = dict(header(), n_jobs=args.n_jobs, main_job_seconds=round(main_seconds, 1),
                   test_rms_N=training["rms_N"], model={"n_branches": held.n_branches, "degree": held.degree},
                   variants=rows)
    write_results(results, Path(args.output))
    print(f"results in {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
