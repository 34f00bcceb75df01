"""The decoupled model's two starts side by side on Bouc-Wen: from the full
PNLSS model by the CPD of its Jacobian tensor (``init="cpd"``, the seed
paper's route) and from the linear model with random branches
(``init="random"``, no full polynomial).

The seed paper's setting: two realisations of two periods at 55 N rms for
training, a third for validation (best iterate and best start), three
branches of degree 10, five starts; the full model of the CPD route is
``PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs",
max_iter=200)``. Scored on the official test multisine and sweep, for
several draws of the training data (``--seeds``). The fit time of the CPD
route includes its full model.

    python benchmarks/bench_decoupled_init.py [--seeds 0 1 2] [--n-jobs 2]
        [--data-dir DIR] [--output FILE]

Results go to ``benchmarks/results/decoupled_init.json``.
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import (DEFAULT_DATA, RESULTS, header, official_test_signals, paper_start,  # noqa: E402
                          paper_training_draw, write_results)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--data-dir", default=DEFAULT_DATA)
    parser.add_argument("--output", default=RESULTS / "decoupled_init.json")
    args = parser.parse_args(argv)

    from sklearn_pnlss import DecoupledPNLSSRegressor

    tests = official_test_signals(args.data_dir)
    rows = []
    for seed in args.seeds:
        data, X, y, X_val, y_val = paper_training_draw(seed)
        P = data.period
        for init in ("cpd", "random"):
            t0 = time.perf_counter()
            start = paper_start(init, data, X, y)
            model = DecoupledPNLSSRegressor(3, n_branches=3, degree=10, period=P, init=init, n_init=5,
                                            n_jobs=args.n_jobs, random_state=0)
            model.fit(start.transform(X), y, X_val=X_val, y_val=y_val)
            row = {"seed": seed, "init": init, "fit_s": time.perf_counter() - t0,
                   "n_nonlinear_params": int(model.n_nonlinear_params_),
                   **{f"db_{name}": -float(model.score(*signals)) for name, signals in tests.items()}}
            rows.append(row)
            print(f"seed {seed}  init={init:6s}  multisine {row['db_multisine']:7.2f} dB  "
                  f"sweep {row['db_sweep']:7.2f} dB  {row['n_nonlinear_params']} parameters  "
                  f"{row['fit_s']:6.1f} s", flush=True)
    results = header()
    results.update({"setting": "3 branches, degree 10, 5 starts; 2 x 2 periods at 55 N, a third for validation",
                    "rows": rows})
    write_results(results, args.output)


if __name__ == "__main__":
    main()
