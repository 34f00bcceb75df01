"""Benchmark of PNLSSRegressor: time per simulation, Jacobian and LM
iteration, total fit time, and (optionally) accuracy and the peer pyvib side
by side.

Cases: n = 3, states only, degrees (2, 3) and (3, 5, 7), on the official
training record (periods 2-5, one realisation) and on 4 realisations x 2
periods of ``make_bouc_wen``; each with one BLAS thread and with the
default thread count. The fit runs ``--iterations`` Levenberg-Marquardt
iterations (tol = 0, so exactly that many unless no step improves); the
library's own functions are wrapped with timers, so the figures are those of
a real fit:

* simulation: one evaluation of the residual over all training segments;
* Jacobian: the sensitivity-recursion kernel over all segments;
* normal equations: the Jacobian plus J^T J and J^T e (what LM needs);
* LM iteration: the LM time divided by the iterations;
* linear start: the BLA and its subspace model;
* check: the new-input check (40 random-phase realisations of the
  training input drawn, the kept iterate simulated on them);
* fit: ``fit`` end to end, all of the above included.

Periods are averaged before fitting (the default, as pyvib and the MATLAB
toolbox do); a third row per record fits all periods, for comparison.

The numba compilation is measured apart, in fresh interpreters (empty cache
and filled cache). With ``--pyvib-path`` (a checkout of pawsen/pyvib) and
``--pyvib-python`` (an interpreter with pyvib's dependencies), the peer
runner ``peers/pyvib_pnlss.py`` is run on the same record, one thread, the
same number of iterations, and the speed-ups are printed. ``--accuracy`` adds
converged fits and their errors on the official test sets (about 10 minutes;
``--accuracy-only`` skips the timings). ``--baseline`` (a checkout of an
earlier commit of this library, e.g. ``git worktree add /tmp/old 32247b8``)
times the official record's fit (degrees (2, 3), periods averaged, one BLAS
thread, ``--iterations``) in fresh interpreters of this checkout and the
baseline in turn, ``--baseline-rounds`` rounds of ``--repeat`` fits each
(and of the fit's linear start alone): the machine's speed drifts by tens
of per cent from hour to hour, so a figure measured at another time says
little, and a paired ratio does (``--baseline-only`` skips the rest).

    python benchmarks/bench_pnlss.py [--iterations 10] [--repeat 3]
        [--pyvib-path /tmp/pyvib --pyvib-python /tmp/pyvib-venv/bin/python]
        [--baseline /tmp/old [--baseline-rounds 5] [--baseline-only]]
        [--accuracy | --accuracy-only] [--data-dir DIR] [--output FILE]

Results go to ``benchmarks/results/pnlss.json``.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import DEFAULT_DATA, RESULTS, first_call, header, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "pnlss.json"
PEER_RUNNER = Path(__file__).resolve().parent / "peers" / "pyvib_pnlss.py"

_FIRST_CALL = """
import json, time
t0 = time.perf_counter()
import numpy as np
from sklearn_pnlss import PNLSSRegressor
from sklearn_pnlss.signals import multisine
t1 = time.perf_counter()
X, _ = multisine(128, fs=1.0, f_band=(0.02, 0.4), n_periods=2, n_realizations=2, random_state=0)
y = np.roll(X, 1, axis=1) + 0.1 * np.roll(X, 2, axis=1) ** 3
fit = lambda: PNLSSRegressor(3, period=128, max_iter=2).fit(X, y).predict(X)
fit()
t2 = time.perf_counter()
fit()
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first_call": t2 - t1, "second_call": t3 - t2}))
"""


# One round of the side by side: the official record's fit, timed in this
# interpreter (whichever checkout PYTHONPATH puts first), one BLAS thread.
_BASELINE_FIT = """
import json, subprocess, sys, time
from pathlib import Path
from threadpoolctl import threadpool_limits
import sklearn_pnlss
from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.datasets import load_bouc_wen_official
data_dir, iterations, repeat = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
off = load_bouc_wen_official(data_dir)
def timed(estimator):
    t0 = time.perf_counter()
    estimator.fit(off.X_train, off.y_train)
    return time.perf_counter() - t0
def fit():
    return timed(PNLSSRegressor(3, degrees=(2, 3), variables="states", period=8192, max_iter=iterations, tol=0.0,
                                average_periods=True, grow_degrees=False))
with threadpool_limits(1):
    fit()  # compiles or loads the kernels
    times = [fit() for _ in range(repeat)]
    linear = [timed(BLAEstimator(3, period=8192)) for _ in range(repeat)]  # the fit's linear start alone
root = Path(sklearn_pnlss.__file__).resolve().parents[1]
commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
print(json.dumps({"times": times, "linear_times": linear, "path": str(root), "commit": commit.stdout.strip()}))
"""


class _Timers:
    """Wall time of each call of the wrapped functions, by name."""

    def __init__(self):
        self.calls = {}

    @contextmanager
    def wrap(self, owner, name, label):
        original = getattr(owner, name)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            out = original(*args, **kwargs)
            self.calls.setdefault(label, []).append(time.perf_counter() - t0)
            return out

        setattr(owner, name, timed)
        try:
            yield
        finally:
            setattr(owner, name, original)


def _timed_fit(X, y, degrees, iterations, average):
    """One instrumented fit; per-call times of the pieces."""
    import sklearn_pnlss.estimators._statespace as fit_steps
    import sklearn_pnlss.statespace.fitting as engine
    from sklearn_pnlss import PNLSSRegressor
    from sklearn_pnlss.statespace.objective import SimulationError
    from sklearn_pnlss.statespace.pnlss import PNLSSModel

    timers = _Timers()
    # The full model's iterations, however many degrees (no growing stages).
    est = PNLSSRegressor(3, degrees=degrees, variables="states", period=8192, max_iter=iterations,
                         tol=0.0, average_periods=average, grow_degrees=False)
    with timers.wrap(SimulationError, "residual", "simulation"), \
            timers.wrap(PNLSSModel, "_sensitivity", "jacobian_segment"), \
            timers.wrap(SimulationError, "normal_equations", "normal_equations"), \
            timers.wrap(engine, "levenberg_marquardt", "lm"), \
            timers.wrap(PNLSSRegressor, "_linear_start", "linear_start"), \
            timers.wrap(fit_steps, "random_phase_inputs", "realisations"), \
            timers.wrap(engine, "_sane_on_new_inputs", "check"):
        t0 = time.perf_counter()
        est.fit(X, y)
        t_fit = time.perf_counter() - t0
    c = timers.calls
    # Kernel calls per normal-equations call: every segment, in its blocks.
    n_seg = len(c["jacobian_segment"]) // len(c["normal_equations"])
    jac = np.add.reduceat(c["jacobian_segment"], np.arange(0, len(c["jacobian_segment"]), n_seg))
    t_lm = sum(c["lm"])
    return {
        "n_params": int(est.n_params_),
        "n_iter": int(est.n_iter_),
        "n_samples_fit": int(sum(seg.Y.shape[0] for seg in _segments_of(X, y, average))),
        "t_simulation_s": statistics.median(c["simulation"]),
        "t_jacobian_s": float(np.median(jac)),
        "t_normal_equations_s": statistics.median(c["normal_equations"]),
        "t_per_iter_s": t_lm / max(est.n_iter_, 1),
        "t_lm_s": t_lm,
        "t_linear_start_s": sum(c["linear_start"]),
        # the new-input check: its realisations drawn, the kept iterate simulated on them
        "t_check_s": sum(c["realisations"]) + sum(c["check"]),
        "t_fit_s": t_fit,
    }


def _segments_of(X, y, average):
    """Training segments as the fit builds them (for the sample count)."""
    from sklearn_pnlss.statespace.segments import make_segments

    Xl = [np.asarray(x) for x in X]
    yl = [np.asarray(v) for v in y]
    return make_segments(Xl, yl, period=8192, n_transient=0, average=average)


def _records(data_dir):
    from sklearn_pnlss.datasets import load_bouc_wen_official, make_bouc_wen

    records = {}
    if (Path(data_dir) / "train_multisine_official.mat").is_file():
        off = load_bouc_wen_official(data_dir)
        records["official record, periods 2-5"] = (off.X_train, off.y_train)
    gen = make_bouc_wen(n_realizations=4, n_periods=2, random_state=0)
    records["make_bouc_wen 4 x 2 periods"] = (gen.X_train, gen.y_train)
    return records


def _speed(data_dir, iterations, repeat):
    rows = []
    for record, (X, y) in _records(data_dir).items():
        for degrees in ((2, 3), (3, 5, 7)):
            for average in (True, False):
                if not average and degrees != (2, 3):
                    continue
                for threads in (1, None):
                    limit = threadpool_limits(1) if threads == 1 else nullcontext()
                    with limit:
                        runs = [_timed_fit(X, y, degrees, iterations, average) for _ in range(repeat)]
                    row = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
                    row.update(record=record, degrees=list(degrees), averaged=average,
                               threads=1 if threads == 1 else "default")
                    rows.append(row)
                    print(f"  {record:30s} {str(degrees):10s} {'avg' if average else 'all':3s} "
                          f"{str(row['threads']):>7s} | {row['n_params']:4.0f} par {row['n_samples_fit']:6.0f} smp | "
                          f"sim {1e3 * row['t_simulation_s']:6.1f} ms  jac {1e3 * row['t_jacobian_s']:6.1f} ms  "
                          f"J'J {1e3 * row['t_normal_equations_s']:6.1f} ms  iter {1e3 * row['t_per_iter_s']:6.1f} ms  "
                          f"linear {row['t_linear_start_s']:5.2f} s  check {row['t_check_s']:5.3f} s  "
                          f"fit {row['t_fit_s']:6.2f} s "
                          f"({row['n_iter']:.0f} it)", flush=True)
    return rows


def _accuracy(data_dir):
    from sklearn_pnlss import PNLSSRegressor
    from sklearn_pnlss.datasets import load_bouc_wen_official, make_bouc_wen

    off = load_bouc_wen_official(data_dir)
    gen = make_bouc_wen(random_state=0)
    # (3, 5, 7), 217 parameters: its error is dominated by the rare large
    # excursions of the response, which differ from one realisation to the
    # next; fitted on five realisations it is 1.5 dB worse on new ones than
    # on its own, on twenty the gap closes. The last realisations keep the
    # best iterate. Two draws of twenty, each fitted with the degrees grown
    # one at a time (the default) and directly, show what growing buys.
    five = make_bouc_wen(n_realizations=6, random_state=0)
    P = 8192
    cases = [
        ("official record", "states", (2, 3), off.X_train, off.y_train, {}, 200, "auto"),
        ("make_bouc_wen 2 x 2", "states", (2, 3), gen.X_train, gen.y_train, {}, 200, "auto"),
        ("make_bouc_wen 2 x 2", "states_inputs", (2, 3), gen.X_train, gen.y_train, {}, 200, "auto"),
        ("make_bouc_wen 5 x 2 + 1 val", "states", (3, 5, 7), five.X_train[:5], five.y_train[:5],
         {"X_val": five.X_train[5:, P:], "y_val": five.y_train[5:, P:]}, 200, "auto"),
    ]
    for seed in (0, 7):
        twenty = make_bouc_wen(n_realizations=22, random_state=seed, n_jobs=-1)
        for grow in ("auto", False):
            cases.append((f"make_bouc_wen 20 x 2 + 2 val, random_state={seed}", "states", (3, 5, 7),
                          twenty.X_train[:20], twenty.y_train[:20],
                          {"X_val": twenty.X_train[20:, P:], "y_val": twenty.y_train[20:, P:]}, 300, grow))
    rows = []
    for record, variables, degrees, X, y, fit_kw, max_iter, grow in cases:
        est = PNLSSRegressor(3, degrees=degrees, variables=variables, period=P, max_iter=max_iter, n_jobs=-1,
                             grow_degrees=grow)
        t0 = time.perf_counter()
        est.fit(X, y, **fit_kw)
        t = time.perf_counter() - t0
        row = {
            "record": record, "variables": variables, "degrees": list(degrees),
            "degree_stages": [list(d) for d in est.degree_stages_],
            "n_params": int(est.n_params_), "n_nonlinear_params": int(est.n_nonlinear_params_),
            "n_iter": int(est.n_iter_), "best_iteration": int(est.best_iteration_), "fit_s": t,
            "train_cost_db": float(10 * np.log10(est.cost_history_[-1] / sum(len(v) for v in y) * 1.0)),
            "db_multisine": float(-est.score(off.X_test_multisine, off.y_test_multisine)),
            "db_sweep": float(-est.score(off.X_test_sweep, off.y_test_sweep)),
        }
        rows.append(row)
        print(f"  {record:46s} {variables:13s} {str(degrees):10s} {len(est.degree_stages_)} stage(s) {row['n_params']:4d} par | "
              f"multisine {row['db_multisine']:7.2f} dB  sweep {row['db_sweep']:7.2f} dB | "
              f"{row['n_iter']:3d} it  {t:6.1f} s", flush=True)
    return rows


def _peer(pyvib_path, pyvib_python, data_dir, iterations):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    out = subprocess.run(
        [pyvib_python, str(PEER_RUNNER), "--pyvib-path", pyvib_path, "--data-dir", str(data_dir),
         "--max-iter", str(iterations)],
        env=env, check=True, capture_output=True, text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _baseline(path, data_dir, iterations, repeat, rounds):
    """This checkout's and the baseline's fit times, in fresh interpreters
    in turn (see ``--baseline``): each round's medians and their ratio."""
    here = str(Path(__file__).resolve().parents[1])

    def round_of(checkout):
        # run from the checkout: "-c" puts the working directory first on the path
        env = dict(os.environ, PYTHONPATH=checkout)
        out = subprocess.run([sys.executable, "-c", _BASELINE_FIT, str(Path(data_dir).resolve()), str(iterations),
                              str(repeat)], env=env, cwd=checkout, check=True, capture_output=True, text=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    runs = []
    for k in range(rounds):
        ours, theirs = round_of(here), round_of(str(path))
        runs.append({"ours_s": statistics.median(ours["times"]), "baseline_s": statistics.median(theirs["times"]),
                     "ours_linear_s": statistics.median(ours["linear_times"]),
                     "baseline_linear_s": statistics.median(theirs["linear_times"])})
        last = runs[-1]
        print(f"  round {k + 1}: this checkout {last['ours_s']:.3f} s (linear start {last['ours_linear_s']:.3f}),"
              f" baseline {theirs['commit']} {last['baseline_s']:.3f} s ({last['baseline_linear_s']:.3f})", flush=True)
    ratios = [r["ours_s"] / r["baseline_s"] for r in runs]
    summary = {"baseline_commit": theirs["commit"], "commit": ours["commit"], "iterations": iterations,
               "fits_per_round": repeat, "rounds": runs,
               "ours_median_s": statistics.median(r["ours_s"] for r in runs),
               "baseline_median_s": statistics.median(r["baseline_s"] for r in runs),
               "ratio_median": statistics.median(ratios),
               "ours_linear_median_s": statistics.median(r["ours_linear_s"] for r in runs),
               "baseline_linear_median_s": statistics.median(r["baseline_linear_s"] for r in runs),
               "linear_ratio_median": statistics.median(r["ours_linear_s"] / r["baseline_linear_s"] for r in runs)}
    print(f"  median: this checkout {summary['ours_median_s']:.3f} s, baseline {summary['baseline_median_s']:.3f} s, "
          f"ratio {summary['ratio_median']:.2f} (paired by round); the linear start alone "
          f"{summary['ours_linear_median_s']:.3f} s against {summary['baseline_linear_median_s']:.3f} s, "
          f"ratio {summary['linear_ratio_median']:.2f}")
    return summary


def _store(results, section, value):
    """A section measured by this run, with the run's date (the sections
    not rerun keep theirs)."""
    results[section], results[f"{section}_date"] = value, results["date"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=str(DEFAULT_DATA))
    parser.add_argument("--iterations", type=int, default=10, help="LM iterations of the timed fits (default 10)")
    parser.add_argument("--repeat", type=int, default=3, help="timed fits per case; medians reported (default 3)")
    parser.add_argument("--accuracy", action="store_true", help="also run converged fits and report test errors")
    parser.add_argument("--accuracy-only", action="store_true",
                        help="only the converged fits; the other results in --output are kept")
    parser.add_argument("--pyvib-path", help="checkout of pawsen/pyvib to run side by side")
    parser.add_argument("--pyvib-python", default=sys.executable, help="interpreter with pyvib's dependencies")
    parser.add_argument("--baseline", help="checkout of an earlier commit of this library to time side by side")
    parser.add_argument("--baseline-rounds", type=int, default=5, help="rounds of the side by side (default 5)")
    parser.add_argument("--baseline-only", action="store_true",
                        help="only the side by side; the other results in --output are kept")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    args = parser.parse_args(argv)
    # The sections not rerun (the converged fits, the peer) are kept as they
    # were measured, each with the date of its run.
    previous = json.loads(Path(args.output).read_text()) if Path(args.output).exists() else {}
    results = header()
    for section in ("speed", "compile", "accuracy", "peer", "baseline"):
        if section in previous:
            results[section] = previous[section]
            results[f"{section}_date"] = previous.get(f"{section}_date", previous.get("date"))
    if args.baseline:
        print(f"side by side with {args.baseline} ({args.iterations} iterations, one BLAS thread, "
              f"{args.baseline_rounds} rounds of {args.repeat} fits)")
        _store(results, "baseline", _baseline(args.baseline, args.data_dir, args.iterations, args.repeat,
                                              args.baseline_rounds))
        if args.baseline_only:
            write_results(results, args.output)
            return
    if args.accuracy_only:
        print("accuracy (converged fits, official test sets)")
        _store(results, "accuracy", _accuracy(args.data_dir))
        write_results(results, args.output)
        return

    print("numba compilation (first fit in a fresh interpreter, small problem)")
    with tempfile.TemporaryDirectory() as empty_cache:
        cold = first_call(_FIRST_CALL, empty_cache)
    warm = first_call(_FIRST_CALL)
    _store(results, "compile", {"cold_cache": cold, "warm_cache": warm})
    print(f"  cold cache: compile {cold['compile_or_load']:.2f} s;  warm cache: load {warm['compile_or_load']:.2f} s")

    print(f"timed fits ({args.iterations} LM iterations, median of {args.repeat})")
    _store(results, "speed", _speed(args.data_dir, args.iterations, args.repeat))

    if args.pyvib_path:
        print(f"peer: pyvib from {args.pyvib_path}, one thread, {args.iterations} iterations")
        peer = _peer(args.pyvib_path, args.pyvib_python, args.data_dir, args.iterations)
        ours = next(r for r in results["speed"] if r["record"].startswith("official") and r["degrees"] == [2, 3]
                    and r["averaged"] and r["threads"] == 1)
        ratios = {
            "jacobian": peer["t_jacobian_s"] / ours["t_jacobian_s"],
            "lm_iteration": peer["t_per_iter_s"] / ours["t_per_iter_s"],
            "fit_end_to_end": peer["t_total_s"] / ours["t_fit_s"],
        }
        _store(results, "peer", {"pyvib": peer, "speedup": ratios})
        print(f"  pyvib: jacobian {peer['t_jacobian_s']:.2f} s, iteration {peer['t_per_iter_s']:.2f} s, "
              f"fit {peer['t_total_s']:.1f} s ({peer['n_iter']} it); "
              f"test {peer['db_multisine']:.2f} / {peer['db_sweep']:.2f} dB")
        print(f"  speed-up: jacobian x{ratios['jacobian']:.0f}, iteration x{ratios['lm_iteration']:.0f}, "
              f"fit end to end x{ratios['fit_end_to_end']:.0f}")

    if args.accuracy:
        print("accuracy (converged fits, official test sets)")
        _store(results, "accuracy", _accuracy(args.data_dir))
    write_results(results, args.output)


if __name__ == "__main__":
    main()
