"""Small data, large model: does a fitted model lose to its own linear start
on new inputs of its training level?

Bouc-Wen, PNLSS degrees (3, 5, 7) on the states (217 parameters), fitted on
three realisations of two periods at 55 N rms (``make_bouc_wen``, one data
draw per seed) and simulated on 14 new noiseless realisations at 50 N (other
seeds), each scored against the linear start (the fitted BLA) on the same
signal. Four ways to fit, each on every draw:

* ``unchecked``: the last iterate, on all three realisations (the library
  before the new-input check; the check is switched off);
* ``checked``: the default, all three realisations, the kept iterate checked
  on 40 new random-phase realisations of the training inputs
  (:func:`~sklearn_pnlss.statespace.new_inputs.random_phase_inputs`) and
  replaced by an earlier one when it runs away on any;
* ``validation``: two realisations for the fit, the third for validation
  (the iterate best on it), the check switched off;
* ``validation_checked``: the same with the check.

Regularisation is not measured: the fit has no penalty term.

    python benchmarks/bench_small_data.py [--seeds 0 1 2 3 4 5] [--n-jobs 2] [--output FILE]

Results go to ``benchmarks/results/small_data.json``.
"""
import argparse
import sys
import time
import warnings
from contextlib import contextmanager
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "small_data.json"
N_NEW = 14
ROUTES = ("unchecked", "checked", "validation", "validation_checked")


@contextmanager
def _check(on):
    """The new-input check as the library has it, or switched off."""
    if on:
        yield
        return
    with mock.patch("sklearn_pnlss.estimators._statespace.random_phase_inputs", lambda *a, **k: ()):
        yield


def _db(model, X, Y):
    from sklearn_pnlss import DivergenceError
    from sklearn_pnlss.metrics import rms_error

    try:
        return float(rms_error(Y[None], model.predict(X[None]), db=True))
    except DivergenceError:
        return np.inf


def _one_fit(route, data, new, n_jobs):
    from sklearn_pnlss import PNLSSRegressor

    P = data.period
    X, y, kwargs = data.X_train, data.y_train, {}
    if route.startswith("validation"):
        X, y = data.X_train[:2], data.y_train[:2]
        kwargs = dict(X_val=data.X_train[2:, -P:], y_val=data.y_train[2:, -P:])
    model = PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", period=P, n_jobs=n_jobs, random_state=0)
    with _check(route in ("checked", "validation_checked")), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        model.fit(X, y, **kwargs)
        seconds = time.perf_counter() - t0
    model_db = np.array([_db(model, a, b) for a, b in zip(new.X_train, new.y_train)])
    linear_db = np.array([_db(model.linear_model_, a, b) for a, b in zip(new.X_train, new.y_train)])
    runaway = [model.range_excursion(a[None])[0] > 1 for a in new.X_train]
    finite = model_db[np.isfinite(model_db)]
    return {
        "route": route, "fit_s": round(seconds, 1), "n_iter": int(model.n_iter_),
        "kept_iteration": int(model.best_iteration_),
        "warned": any("runs away" in str(w.message) for w in caught),
        "n_worse_than_linear": int(np.sum(model_db > linear_db)),
        "n_runaway": int(np.sum(runaway)),
        "db_mean": float(np.mean(finite)) if finite.size else None,
        "db_worst": float(np.max(model_db)),
        "linear_db_mean": float(np.mean(linear_db)),
        "db": [round(float(v), 2) for v in model_db],
    }


def main(argv=None):
    from sklearn_pnlss.datasets import make_bouc_wen

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(6)))
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)

    rows = []
    for seed in args.seeds:
        data = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, random_state=seed, n_jobs=args.n_jobs)
        new = make_bouc_wen(n_realizations=N_NEW, n_periods=1, rms=50.0, noise_rms=0.0,
                            random_state=1050 + seed, n_jobs=args.n_jobs)
        for route in ROUTES:
            row = {"seed": seed, **_one_fit(route, data, new, args.n_jobs)}
            rows.append(row)
            print(f"seed {seed} {route:<19} {row['fit_s']:6.1f} s  kept {row['kept_iteration']:3d}/{row['n_iter']:3d}"
                  f"  worse than linear {row['n_worse_than_linear']:2d}/{N_NEW}  runaway {row['n_runaway']:2d}"
                  f"  mean {row['db_mean']:7.2f} dB  worst {row['db_worst']:7.2f} dB"
                  f"  (linear {row['linear_db_mean']:.2f} dB)", flush=True)
    summary = {}
    for route in ROUTES:
        mine = [r for r in rows if r["route"] == route]
        summary[route] = {
            "draws": len(mine),
            "draws_worse_than_linear_somewhere": sum(r["n_worse_than_linear"] > 0 for r in mine),
            "signals_worse_than_linear": sum(r["n_worse_than_linear"] for r in mine),
            "signals": N_NEW * len(mine),
            "median_db_mean": float(np.median([r["db_mean"] for r in mine])),
            "median_fit_s": float(np.median([r["fit_s"] for r in mine])),
        }
        s = summary[route]
        print(f"{route:<19} worse than linear on {s['signals_worse_than_linear']}/{s['signals']} signals "
              f"({s['draws_worse_than_linear_somewhere']}/{s['draws']} draws), median of the draws' mean "
              f"{s['median_db_mean']:.2f} dB, median fit {s['median_fit_s']:.1f} s", flush=True)
    results = header()
    results.update({"setup": "Bouc-Wen PNLSS (3, 5, 7) states, 3 realisations x 2 periods at 55 N; "
                             f"{N_NEW} new 50 N realisations per draw",
                    "rows": rows, "summary": summary})
    write_results(results, args.output)


if __name__ == "__main__":
    main()
