"""The gap diagnosis' black box: started from the linear model or from a
full PNLSS model.

The black box is a decoupled PNLSS model (3 states, 3 branches, degree 7,
30 iterations) fitted to a diagnosis' training signals (their outputs less
their means), the yardstick of how much of the gap a model without physics
closes. This script fits it both ways on withheld-effect cases of
``gap_withheld.py`` and scores each on the case's validation signals (a
steady-state multisine and a sweep from rest, outputs less their means):

- ``linear``: the library's setting (``gap.fitting.black_box``), random
  branches on the linear model, the better of ``N_STARTS`` by training
  error;
- ``linear, one start``: the same with a single start;
- ``pnlss``: a full PNLSS model first (degrees 2 and 3 in the states and
  input, 30 iterations), the decoupled model started from the CPD of its
  Jacobian tensor (the setting before).

Per case and start: the CPU seconds of the fit (one thread) and the
validation rms error of each signal in dB. Results in
``results/black_box.json``::

    python benchmarks/bench_black_box.py
"""
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import gap_withheld as gw  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402

#: Family e's single effects (their second seed) and two of family t's pairs.
CASES = [("e", "hysteresis", None, 1), ("e", "cubic_stiffness", None, 1), ("e", "second_mode", None, 1),
         ("t", ("cubic_stiffness", 1), "quadratic_damping", 0), ("t", ("backlash", 0), "quadratic_damping", 1)]


def _fits(X, Y, period, seed):
    from sklearn_pnlss import DecoupledPNLSSRegressor, PNLSSRegressor
    from sklearn_pnlss.gap.fitting import black_box as bb

    common = dict(n_branches=bb.N_BRANCHES, degree=bb.DEGREE, period=period, max_iter=30, n_jobs=1,
                  random_state=seed)
    return {
        "linear": lambda: DecoupledPNLSSRegressor(bb.N_STATES, init="random", n_init=bb.N_STARTS,
                                                  **common).fit(X, Y),
        "linear, one start": lambda: DecoupledPNLSSRegressor(bb.N_STATES, init="random", n_init=1,
                                                             **common).fit(X, Y),
        "pnlss": lambda: DecoupledPNLSSRegressor(
            bb.N_STATES, n_init=1, start_model=PNLSSRegressor(bb.N_STATES, degrees=(2, 3), variables="states_inputs",
                                                              period=period, max_iter=30, random_state=seed),
            **common).fit(X, Y),
    }


def run_case(family, first, second, seed):
    truth = gw.pair_truth(first, second, seed)[0] if family == "t" else gw.CASES[first][seed]
    u, y, u_val, y_val, _, period, _ = gw.make_data(truth, seed)
    X, Y = [x[:, None] for x in u], [v[:, None] - v.mean() for v in y]
    row = {"family": family, "case": first if family == "e" else f"{first[0]} + {second}", "seed": seed}
    for label, fit in _fits(X, Y, period, seed).items():
        t0 = time.process_time()
        model = fit()
        cpu = time.process_time() - t0
        errors = []
        for x, v in zip(u_val, y_val):
            p = np.asarray(model.predict(x[:, None]))[:, 0]
            errors.append(float(10 * np.log10(np.mean(((v - v.mean()) - (p - p.mean())) ** 2))))
        row[label] = {"cpu_s": cpu, "validation_db": errors}
        print(f"{row['case']:40s} {label:18s} cpu {cpu:5.1f} s  validation {np.round(errors, 2)} dB", flush=True)
    return row


def main():
    from threadpoolctl import threadpool_limits

    warnings.filterwarnings("ignore")
    with threadpool_limits(1):  # as in a diagnosis: one BLAS thread per worker
        rows = [run_case(*case) for case in CASES]
    results = header()
    results["rows"] = rows
    write_results(results, RESULTS / "black_box.json")


if __name__ == "__main__":
    main()
