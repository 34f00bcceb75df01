"""Do the fitted models stay bounded on new signals of the training kind?

Every model that the main job, the README or the gallery shows is fitted as
they fit it, once with the default ``extrapolation="hold"`` (the
nonlinearity held at the edge of its trusted range: bounded by construction)
and once with ``extrapolation="polynomial"`` (the plain polynomial), and
simulated on

* 20 new multisine realisations at 50 N rms (the test level) and 20 at 60 N
  (above the training level), noiseless, in periodic steady state;
* the official test multisine and sweep (when ``--data-dir`` has them).

For each model it counts the signals on which the simulation diverges, and
those on which it runs away (its nonlinearity's variables go past their
trusted range by more than its width: a bounded model on an orbit it was
never fitted for), and gives the rms errors in dB of the others.

Models: PNLSS (2, 3) states only and states and input on the main job's data
(two realisations of two periods at 55 N, a third for validation); the
decoupled model r = 3, d = 10 (the main job's) and r = 3, d = 11 (the best
of at most 60 nonlinear parameters of the seed paper's grid,
``benchmarks/results/decoupled_grid.json``) from
the states-and-input model; PNLSS (3, 5, 7) states only, grown, on twenty
realisations at 50 N (``bench_pnlss.py``'s accuracy case).

    python benchmarks/bench_bounded.py [--data-dir DIR] [--n-jobs 2] [--quick] [--output FILE]

``--quick`` leaves out the (3, 5, 7) model (about 4 of the 8 minutes).
Results go to ``benchmarks/results/bounded.json``.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import DEFAULT_DATA, RESULTS, header, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "bounded.json"
N_NEW = 20
LEVELS = (50.0, 60.0)


def _fit_models(names, extrapolation, n_jobs):
    """{name: (fitted estimator, fit seconds)} with the given extrapolation."""
    from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor
    from sklearn_pnlss.datasets import make_bouc_wen
    from sklearn_pnlss.utils.handover import attach_stage

    out = {}
    main = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, random_state=0, n_jobs=n_jobs)
    P, fs = main.period, main.fs
    X, y = main.X_train[:2], main.y_train[:2]
    X_val, y_val = main.X_train[2:, -P:], main.y_train[2:, -P:]

    def timed(name, make, *args, **kwargs):
        t0 = time.perf_counter()
        model = make().fit(*args, **kwargs)
        out[name] = (model, time.perf_counter() - t0)
        return model

    common = dict(period=P, extrapolation=extrapolation)
    if "pnlss_states_23" in names:
        timed("pnlss_states_23", lambda: PNLSSRegressor(3, degrees=(2, 3), variables="states", max_iter=40,
                                                        linear_model=BLAEstimator(3, period=P, fs=fs), **common), X, y)
    si = timed("pnlss_si_23", lambda: PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", max_iter=200,
                                                     linear_model=BLAEstimator(3, period=P, fs=fs), **common), X, y)
    for d in (10, 11):
        name = f"decoupled_r3_d{d}"
        if name in names:
            timed(name, lambda d=d: DecoupledPNLSSRegressor(3, n_branches=3, degree=d, n_init=5, max_iter=100,
                                                            n_jobs=n_jobs, random_state=0, **common),
                  attach_stage(X, si), y, X_val=X_val, y_val=y_val)
    if "pnlss_states_357" in names:
        big = make_bouc_wen(n_realizations=22, n_periods=2, rms=50.0, random_state=0, n_jobs=n_jobs)
        timed("pnlss_states_357", lambda: PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", max_iter=300,
                                                         n_jobs=n_jobs, **common),
              big.X_train[:20], big.y_train[:20], X_val=big.X_train[20:, -P:], y_val=big.y_train[20:, -P:])
    return {name: out[name] for name in names}


def _outcome(model, X, y):
    """("ok", dB), ("runaway", dB) or ("diverged", None) on one signal."""
    from sklearn_pnlss import DivergenceError
    from sklearn_pnlss.metrics import rms_error

    try:
        y_pred = model.predict(X)
    except DivergenceError:
        return "diverged", None
    db = float(rms_error(y, y_pred, db=True))
    return ("runaway" if model.range_excursion(X)[0] > 1 else "ok"), db


def _summarise(outcomes):
    dbs = [db for kind, db in outcomes if kind == "ok"]
    return {
        "n_signals": len(outcomes),
        "n_diverged": sum(kind == "diverged" for kind, _ in outcomes),
        "n_runaway": sum(kind == "runaway" for kind, _ in outcomes),
        "db_mean": float(np.mean(dbs)) if dbs else None,
        "db_worst": float(np.max(dbs)) if dbs else None,
        "db_best": float(np.min(dbs)) if dbs else None,
    }


def main(argv=None):
    from sklearn_pnlss.datasets import load_bouc_wen_official, make_bouc_wen

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=str(DEFAULT_DATA))
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="leave out the (3, 5, 7) model")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)

    names = ["pnlss_states_23", "pnlss_si_23", "decoupled_r3_d10", "decoupled_r3_d11"]
    if not args.quick:
        names.append("pnlss_states_357")
    # New signals, never used for fitting or selection: other seeds than any fit.
    new = {level: make_bouc_wen(n_realizations=N_NEW, n_periods=1, rms=level, noise_rms=0.0,
                                random_state=1000 + int(level), n_jobs=args.n_jobs) for level in LEVELS}
    official = None
    if Path(args.data_dir, "uval_multisine.mat").exists():
        official = load_bouc_wen_official(args.data_dir)
    rows = []
    for extrapolation in ("hold", "polynomial"):
        for name, (model, seconds) in _fit_models(names, extrapolation, args.n_jobs).items():
            row = {"model": name, "extrapolation": extrapolation, "n_params": int(model.n_params_),
                   "fit_s": round(seconds, 1)}
            for level, data in new.items():
                row[f"new_{int(level)}N"] = _summarise(
                    [_outcome(model, X[None], Y[None]) for X, Y in zip(data.X_train, data.y_train)])
            if official is not None:
                for key in ("multisine", "sweep"):
                    kind, db = _outcome(model, official[f"X_test_{key}"], official[f"y_test_{key}"])
                    row[f"official_{key}"] = {"outcome": kind, "db": db}
            rows.append(row)
            print(_format(row), flush=True)
    results = header()
    results.update({"n_new_signals_per_level": N_NEW, "levels_N": list(LEVELS), "models": rows})
    write_results(results, args.output)


def _format(row):
    parts = [f"{row['model']:<18}{row['extrapolation']:<11}{row['n_params']:>5} par {row['fit_s']:>6.1f} s"]
    for level in LEVELS:
        s = row[f"new_{int(level)}N"]
        mean = f"{s['db_mean']:7.2f}" if s["db_mean"] is not None else "      -"
        parts.append(f"{int(level)} N: {s['n_diverged']:2d} div {s['n_runaway']:2d} run, mean {mean} dB")
    for key in ("multisine", "sweep"):
        if f"official_{key}" in row:
            o = row[f"official_{key}"]
            parts.append(f"{key} " + (f"{o['db']:.2f} dB" if o["db"] is not None else "diverged")
                         + (" (runaway)" if o["outcome"] == "runaway" else ""))
    return " | ".join(parts)


if __name__ == "__main__":
    main()
