"""The field's measured benchmarks by their official splits, beside the
published results: WH2009, cascaded tanks and EMPS (the F-16 has its own
script, ``bench_f16.py``).

Each benchmark is read with :func:`sklearn_pnlss.datasets.load_benchmark`
(the official loader's split and state-initialisation window), fitted on
its estimation record only, simulated from rest over its test record, and
scored by the test rms error in the unit the field reports, skipping the
initialisation window as the official scorer does; NRMSE and fit % beside
it. No test data enter training or selection.

    python benchmarks/bench_field.py [--only NAME ...] [--data-dir DIR] [--output FILE]

Results go to ``benchmarks/results/field.json``: per benchmark
``test_rmse`` (in ``unit``), ``nrmse``, ``fit_percent``, ``fit_s``, the
model's settings, and the published figures.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402

DEFAULT_DATA = REPO.parent / "shared" / "data"
DEFAULT_OUTPUT = RESULTS / "field.json"
# Published test rms errors (unit of the benchmark's report; see the issue
# and Champneys et al., SYSID 2024).
PUBLISHED = {
    "wh2009": {"PNLSS (Paduart et al. 2012)": 0.42, "DT SUBNET (best)": 0.241},
    "cascaded_tanks": {"PNLSS (Relan et al. 2017)": 0.45, "grey box (Worden et al. 2018)": 0.191,
                       "CT SUBNET": 0.306},
    "emps": {"dynoNet": 2.64, "CT SUBNET": 4.61, "linear": 5.53},
}


def models(name):
    """The library's models for one benchmark: (label, settings, factory)
    pairs; each factory returns an unfitted estimator (or Pipeline)."""
    from sklearn.pipeline import make_pipeline

    from sklearn_pnlss import BLAEstimator, PNLSSRegressor

    n, fs = {"wh2009": (6, 51200.0), "cascaded_tanks": (2, 0.25), "emps": (2, 1000.0)}[name]
    rows = [("BLA", {"n_states": n}, lambda: BLAEstimator(n, fs=fs))]
    if name in ("wh2009", "cascaded_tanks"):
        pnlss = {"degrees": (2, 3), "variables": "states_inputs", "equations": "both", "max_iter": 100}
        rows.append(("PNLSS", {"n_states": n, **pnlss},
                     lambda: make_pipeline(BLAEstimator(n, fs=fs), PNLSSRegressor(n, **pnlss))))
    return rows


def run(name, data_dir):
    from sklearn_pnlss import DivergenceError
    from sklearn_pnlss.datasets import load_benchmark
    from sklearn_pnlss.metrics import fit_percent, nrmse, rms_error

    data = load_benchmark(name, data_dir)
    rows = []
    for label, settings, make in models(name):
        model = make()
        t0 = time.perf_counter()
        try:
            model.fit(data.X_train, data.y_train)
            fit_s = time.perf_counter() - t0
            pred = model.predict(data.X_test)
        except (ValueError, DivergenceError) as exc:  # a model that cannot be fitted or simulated is a row too
            rows.append({"model": label, "settings": settings, "error": str(exc)})
            print(f"{name:15s} {label:8s} failed: {exc}", flush=True)
            continue
        row = {"model": label, "settings": settings, "fit_s": fit_s, "unit": data.report_unit,
               "test_rmse": data.report_scale * rms_error(data.y_test, pred, skip=data.skip),
               "nrmse": nrmse(data.y_test, pred, skip=data.skip),
               "fit_percent": fit_percent(data.y_test, pred, skip=data.skip)}
        rows.append(row)
        print(f"{name:15s} {label:8s} test rms {row['test_rmse']:8.4f} {data.report_unit:3s} "
              f"NRMSE {row['nrmse']:.4f}  fit {row['fit_percent']:6.2f} %  ({fit_s:7.1f} s)", flush=True)
    published = "; ".join(f"{k} {v}" for k, v in PUBLISHED[name].items())
    print(f"{name:15s} published: {published} {data.report_unit}", flush=True)
    return {"rows": rows, "unit": data.report_unit, "skip": data.skip, "published": PUBLISHED[name]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=sorted(PUBLISHED), default=sorted(PUBLISHED))
    parser.add_argument("--data-dir", default=DEFAULT_DATA)
    parser.add_argument("--output", default=DEFAULT_OUTPUT)
    args = parser.parse_args(argv)
    output = Path(args.output)
    # Rerunning one benchmark keeps the others' rows.
    results = json.loads(output.read_text()) if output.is_file() else {}
    results.update(header())
    results.setdefault("benchmarks", {})
    for name in args.only:
        results["benchmarks"][name] = run(name, args.data_dir)
    write_results(results, output)


if __name__ == "__main__":
    main()
