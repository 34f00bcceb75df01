"""Do the decoupled model's Levenberg-Marquardt steps need the Legendre basis?

The same decoupled model (3 branches of degree 11 from the states-and-input
PNLSS (2, 3) start, the seed paper's set-up) is fitted from ``--n-starts``
single starts (``n_init=1``, ``random_state`` 0, 1, ...) twice: with the
library's steps (branch coefficients stepped in Legendre polynomials over
each branch's range, ``DecoupledModel.step_basis``) and with the plain
powers of ``z`` (the step basis switched off for this run only). Each start
is scored on the official test multisine and sweep. Training: two
realisations of two periods at 55 N rms (``make_bouc_wen``'s ``--seed``),
a third for validation, as in ``bench_decoupled_grid.py``.

    python benchmarks/bench_step_basis.py [--seed 1] [--n-starts 8] [--max-iter 300]
        [--data-dir DIR] [--output FILE]

About 3 minutes on 2 cores (starts run two at a time). Results go to
``benchmarks/results/step_basis.json``.
"""
import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

from joblib import Parallel, delayed

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import DEFAULT_DATA, RESULTS, header, score_test_signals, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "step_basis.json"


def _fit_and_score(start, X, y, val, official, random_state, max_iter, P):
    from sklearn_pnlss import DecoupledPNLSSRegressor
    from sklearn_pnlss.utils.handover import attach_stage

    model = DecoupledPNLSSRegressor(3, n_branches=3, degree=11, period=P, n_init=1, max_iter=max_iter,
                                    random_state=random_state)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(attach_stage(X, start), y, X_val=val[0], y_val=val[1])
    return {"random_state": random_state, "n_iter": int(model.n_iter_),
            "validation_db": float(model.init_scores_[0]), **score_test_signals(model, official)}


def main(argv=None):
    from sklearn_pnlss import PNLSSRegressor
    from sklearn_pnlss.datasets import load_bouc_wen_official, make_bouc_wen
    from sklearn_pnlss.statespace.decoupled import DecoupledModel

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=str(DEFAULT_DATA))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--n-starts", type=int, default=8)
    parser.add_argument("--max-iter", type=int, default=300)
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)

    data = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, random_state=args.seed)
    P = data.period
    X, y = data.X_train[:2], data.y_train[:2]
    val = (data.X_train[2:, P:], data.y_train[2:, P:])
    official = load_bouc_wen_official(args.data_dir)
    start = PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=P, max_iter=200).fit(X, y)

    legendre_steps = DecoupledModel.step_basis
    results = header()
    results.update({"seed": args.seed, "n_branches": 3, "degree": 11, "max_iter": args.max_iter, "steps": {}})
    for steps in ("legendre", "powers"):
        # Switched off for the comparison only: the library always steps in Legendre polynomials.
        DecoupledModel.step_basis = legendre_steps if steps == "legendre" else (lambda self, states_inputs: None)
        t0 = time.perf_counter()
        runs = Parallel(n_jobs=2, prefer="threads")(
            delayed(_fit_and_score)(start, X, y, val, official, k, args.max_iter, P) for k in range(args.n_starts)
        )
        seconds = time.perf_counter() - t0
        ms = [r["multisine"] for r in runs if r["multisine"] is not None]
        summary = {"starts": runs, "median_multisine_db": statistics.median(ms) if ms else None,
                   "best_multisine_db": min(ms) if ms else None, "n_diverged": len(runs) - len(ms),
                   "seconds": seconds}
        results["steps"][steps] = summary
        print(f"{steps:>9}: " + " ".join(f"{r['multisine']:.2f}" if r["multisine"] is not None else "div"
                                         for r in runs)
              + f" | median {summary['median_multisine_db']:.2f} dB, best {summary['best_multisine_db']:.2f} dB,"
              f" {seconds:.0f} s", flush=True)
    DecoupledModel.step_basis = legendre_steps
    write_results(results, args.output)


if __name__ == "__main__":
    main()
