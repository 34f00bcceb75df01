"""The decoupled model's branches in powers and in signed powers, side by
side on Bouc-Wen.

Branches in signed powers (``branch_basis="signed_powers"``: ``z``,
``z |z|``, ``z**3``, ``z**3 |z|`` ...) are odd and change a structure's
stiffness and damping in proportion to the amplitude, as friction,
clearances and hysteresis do; in powers ``z**3`` changes them with its
square; and the two starts, from the linear model and from the full
model, side by side. The seed paper's setting: two
realisations of two periods at 55 N rms for training, a third for
validation (best iterate and best start), three branches of degree 10 (51
nonlinear parameters), five starts from the linear model
(``init="random"``) and, with ``--cpd``, from the seed paper's full model
(``init="cpd"``, its fit counted in the time); scored on the official test
multisine and sweep for several draws of the training data (``--seeds``).

    python benchmarks/bench_branch_basis.py [--seeds 0 1 2 3 4 5] [--cpd]
        [--n-jobs 2] [--data-dir DIR] [--output FILE]

Results go to ``benchmarks/results/branch_basis.json``.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import (DEFAULT_DATA, RESULTS, header, official_test_signals, paper_start,  # noqa: E402
                          paper_training_draw, write_results)

BASES = ("powers", "signed_powers")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    parser.add_argument("--cpd", action="store_true", help="also the starts from the full model")
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--data-dir", default=DEFAULT_DATA)
    parser.add_argument("--output", default=RESULTS / "branch_basis.json")
    args = parser.parse_args(argv)

    from sklearn_pnlss import DecoupledPNLSSRegressor

    tests = official_test_signals(args.data_dir)
    inits = ("random", "cpd") if args.cpd else ("random",)
    rows = []
    for seed in args.seeds:
        data, X, y, X_val, y_val = paper_training_draw(seed)
        P = data.period
        for init in inits:
            t0 = time.perf_counter()
            start = paper_start(init, data, X, y)
            start_s = time.perf_counter() - t0
            for basis in BASES:
                t0 = time.perf_counter()
                model = DecoupledPNLSSRegressor(3, n_branches=3, degree=10, branch_basis=basis, period=P,
                                                init=init, n_init=5, n_jobs=args.n_jobs, random_state=0)
                model.fit(start.transform(X), y, X_val=X_val, y_val=y_val)
                row = {"seed": seed, "init": init, "branch_basis": basis,
                       "fit_s": start_s + time.perf_counter() - t0,
                       "n_nonlinear_params": int(model.n_nonlinear_params_),
                       **{f"db_{name}": -float(model.score(*signals)) for name, signals in tests.items()}}
                rows.append(row)
                print(f"seed {seed}  init={init:6s}  {basis:13s}  multisine {row['db_multisine']:7.2f} dB  "
                      f"sweep {row['db_sweep']:7.2f} dB  {row['n_nonlinear_params']} parameters  "
                      f"{row['fit_s']:5.1f} s", flush=True)
    median = {init: {basis: {name: float(np.median([r[f"db_{name}"] for r in rows
                                                    if (r["init"], r["branch_basis"]) == (init, basis)]))
                             for name in tests} for basis in BASES} for init in inits}
    for init, by_basis in median.items():
        for basis, figures in by_basis.items():
            print(f"median over {len(args.seeds)} draws, init={init:6s} {basis:13s}: multisine "
                  f"{figures['multisine']:7.2f} dB  sweep {figures['sweep']:7.2f} dB")
    results = header()
    results.update({"setting": "3 branches, degree 10, 5 starts; 2 x 2 periods at 55 N, a third for validation",
                    "rows": rows, "median_db": median})
    write_results(results, args.output)


if __name__ == "__main__":
    main()
