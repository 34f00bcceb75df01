"""Levenberg-Marquardt's damping rule, Nielsen's against the PNLSS
toolbox's, on the same fits from the same starts: the PNLSS models of
``bench_field.py`` (WH2009: 833 parameters, one long measured record; the
cascaded tanks: 33 parameters, 1024 samples; EMPS: the model of its
position's increments, 2 states), the Bouc-Wen quick start
(PNLSS and decoupled models on several training seeds) and the F-16
(2,893 parameters, four levels).

    python benchmarks/bench_lm_schedule.py [--only wh2009 cascaded_tanks emps bouc_wen f16]
        [--max-iter 100] [--seeds 0 1 2] [--data-dir DIR] [--output FILE]

Each fit runs once with ``damping="toolbox"`` (lambda halved on success,
multiplied by 10 on failure) and once with ``damping="nielsen"`` (the
library's rule, see :mod:`sklearn_pnlss.statespace.levenberg_marquardt`);
the rule is swapped in for the run (in the fitting engine and in the
subspace refinement of the linear start), nothing else changes. Printed
and written to ``benchmarks/results/lm_schedule.json``: the training cost
(dB, every tenth iteration and at the end), the test error in the
benchmark's unit and the fit time.
"""
import argparse
import functools
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402

DAMPINGS = ("toolbox", "nielsen")
DEFAULT_DATA = REPO.parent / "shared" / "data"


@contextmanager
def damping_rule(damping):
    """Levenberg-Marquardt with ``damping`` for the block, in its two users:
    the fitting engine and the subspace refinement of the linear start."""
    from sklearn_pnlss.statespace import fitting, subspace
    from sklearn_pnlss.statespace.levenberg_marquardt import levenberg_marquardt

    for module in (fitting, subspace):
        module.levenberg_marquardt = functools.partial(levenberg_marquardt, damping=damping)
    try:
        yield
    finally:
        for module in (fitting, subspace):
            module.levenberg_marquardt = levenberg_marquardt


def cost_trace(model):
    """Training cost in dB, every tenth iteration and the last."""
    db = 10 * np.log10(model.cost_history_)
    return {"cost_db_every_10": [round(float(c), 3) for c in db[::10]], "final_cost_db": float(db[-1]),
            "n_iter": int(model.n_iter_)}


# Each field benchmark's model of bench_field.py that these runs compare.
FIELD_MODELS = {"wh2009": "PNLSS", "cascaded_tanks": "PNLSS", "emps": "PNLSS of the increments, summed"}


def field_benchmark(name, args):
    """The field benchmark's model of bench_field.py, its iterations set to
    ``--max-iter``, scored on the official test split in the field's unit."""
    import bench_field

    from sklearn_pnlss.datasets import load_benchmark
    from sklearn_pnlss.metrics import rms_error

    data = load_benchmark(name, args.data_dir)
    make = {label: factory for label, _, factory in bench_field.models(name)}[FIELD_MODELS[name]]
    rows = []
    for damping in DAMPINGS:
        model = make()
        model.set_params(**{key: args.max_iter for key in model.get_params() if key.endswith("pnlssregressor__max_iter")})
        with damping_rule(damping):
            t0 = time.perf_counter()
            model.fit(data.X_train, data.y_train)
            fit_s = time.perf_counter() - t0
        pred = model.predict(data.X_test, y_init=data.y_test[:, :data.skip])
        final = (model.regressor_ if hasattr(model, "regressor_") else model)[-1]
        row = {"damping": damping, "max_iter": args.max_iter, "fit_s": fit_s, "unit": data.report_unit,
               "test_rmse": data.report_scale * rms_error(data.y_test, pred, skip=data.skip), **cost_trace(final)}
        rows.append(row)
        print(f"{name:15s} {damping:8s} {args.max_iter} it: training cost {row['final_cost_db']:7.2f} dB, "
              f"test {row['test_rmse']:.3f} {data.report_unit} ({fit_s:.1f} s)", flush=True)
    return rows


def bouc_wen(args):
    """The quick start (``python -m sklearn_pnlss``) on each training seed:
    multisine and sweep test errors of the PNLSS and decoupled models."""
    from sklearn_pnlss.app.study import run_study

    rows = []
    for seed in args.seeds:
        for damping in DAMPINGS:
            with damping_rule(damping), tempfile.TemporaryDirectory() as folder:
                summary = run_study(output_dir=folder, random_state=seed, plots=False, progress=False)
            for r in summary["results"]:
                if r["model"] == "bla":
                    continue
                name = r["model"]
                rows.append({"damping": damping, "seed": seed, "model": name, "fit_s": r["fit_time_s"],
                             "multisine_db": r["multisine_db"], "sweep_db": r["sweep_db"]})
                print(f"bouc_wen seed {seed} {damping:8s} {name:9s} multisine {r['multisine_db']:7.2f} dB, "
                      f"sweep {r['sweep_db']:7.2f} dB ({r['fit_time_s']:.0f} s)", flush=True)
    return rows


def f16(args):
    """The F-16 PNLSS model of bench_f16.py (10 states, degrees 2-3 in the
    states, 20 iterations) on levels 1, 3, 5, 7; NRMSE on levels 2, 4, 6."""
    import bench_f16

    from sklearn_pnlss import BLAEstimator, PNLSSRegressor

    X, y, test = bench_f16.load(Path(args.data_dir) / "f16")
    bla = BLAEstimator(10, period=8192, fs=400.0).fit(X, y)
    rows = []
    for damping in DAMPINGS:
        model = PNLSSRegressor(10, degrees=(2, 3), variables="states", period=8192, max_iter=20, tol=0.0)
        with damping_rule(damping):
            t0 = time.perf_counter()
            model.fit(bla.transform(X), y)
            fit_s = time.perf_counter() - t0
        per_level, mean, _ = bench_f16.nrmse(model, test)
        rows.append({"damping": damping, "fit_s": fit_s, "mean_nrmse": mean, "nrmse": per_level,
                     **cost_trace(model)})
        print(f"f16      {damping:8s} 20 it: training cost {rows[-1]['final_cost_db']:7.2f} dB, "
              f"mean NRMSE {mean:.4f} ({fit_s:.0f} s)", flush=True)
    return rows


RUNS = {**{name: functools.partial(field_benchmark, name) for name in FIELD_MODELS}, "bouc_wen": bouc_wen, "f16": f16}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=sorted(RUNS), default=sorted(RUNS))
    parser.add_argument("--max-iter", type=int, default=100,
                        help="iterations of the field benchmarks' fits (default: %(default)s)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="Bouc-Wen training seeds")
    parser.add_argument("--data-dir", default=DEFAULT_DATA)
    parser.add_argument("--output", default=RESULTS / "lm_schedule.json")
    args = parser.parse_args(argv)
    output = Path(args.output)
    import json

    results = json.loads(output.read_text()) if output.is_file() else {}
    results.update(header())
    for name in args.only:
        results[name] = RUNS[name](args)
    write_results(results, output)


if __name__ == "__main__":
    main()
