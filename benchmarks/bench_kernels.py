"""Speed of the compiled time recursions at Bouc-Wen sizes: the simulation
and the Jacobian (sensitivity recursion) of the PNLSS and decoupled models,
in nanoseconds a sample, alone or side by side with an earlier commit.

The models are fitted briefly (a few Levenberg-Marquardt iterations on
``make_bouc_wen`` data: realistic parameters and trusted ranges) by this
checkout and pickled; each kernel is then timed in a fresh interpreter on one
8,192-sample period from rest: ``model._run`` (the simulation) and
``model.segment_jacobian`` (the Jacobian of that segment's error), ``--repeat``
calls each, their minimum and median. ``--baseline CHECKOUT`` times the same
pickled models with that checkout's code (its kernels) in turn with this
one's, ``--baseline-rounds`` rounds, and gives each kernel's median ratio of
the paired minima: the machine's speed drifts from hour to hour, a pair
does not. ``--fit-profile`` adds where one fit of the seed paper's grid
goes (``--fit-profile-model``, 6 branches of degree 11 by default: five
starts of 100 iterations from the states-and-input (2, 3) PNLSS, one BLAS
thread, as a grid worker runs it), by cProfile: the Jacobian kernel, the
normal equations (J^T J, J^T e and the start-state products), the
simulation kernel, the runaway checks, the step's eigendecomposition and
the rest. Results go to ``benchmarks/results/kernels.json``.

    python benchmarks/bench_kernels.py [--repeat 41] [--baseline CHECKOUT
        [--baseline-rounds 3]] [--fit-profile [--fit-profile-model 6 11]]
        [--output FILE]
"""
import argparse
import json
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, commit_of, header, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "kernels.json"
PERIOD = 8192
# (label, estimator, settings): the sizes the seed paper's grid and the
# official record's fits run at
CASES = [
    ("PNLSS (2, 3) states", "PNLSSRegressor", {"degrees": (2, 3), "variables": "states"}),
    ("PNLSS (2, 3) states and input", "PNLSSRegressor", {"degrees": (2, 3), "variables": "states_inputs"}),
    ("decoupled r=3 d=7", "DecoupledPNLSSRegressor", {"n_branches": 3, "degree": 7, "n_init": 1}),
    ("decoupled r=5 d=8", "DecoupledPNLSSRegressor", {"n_branches": 5, "degree": 8, "n_init": 1}),
    ("decoupled r=6 d=11", "DecoupledPNLSSRegressor", {"n_branches": 6, "degree": 11, "n_init": 1}),
]


def fit_models(path):
    """Fit the CASES briefly and pickle ``(label, normalised model, U)`` to
    ``path``."""
    import sklearn_pnlss
    from sklearn_pnlss.datasets import make_bouc_wen

    data = make_bouc_wen(n_realizations=2, n_periods=2, random_state=0)
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a few iterations: the new-input check may keep an earlier iterate
        for label, name, settings in CASES:
            est = getattr(sklearn_pnlss, name)(3, period=PERIOD, max_iter=5, random_state=0, **settings)
            est.fit(data.X_train, data.y_train)
            model = est.model_.normalised
            U = np.ascontiguousarray(est.model_.normalise_inputs(data.X_train[0, :PERIOD]))
            out.append((label, model, U))
    with open(path, "wb") as f:
        pickle.dump(out, f)


def measure(models_path, repeat):
    """Time each pickled model's kernels with the code this interpreter
    imports; returns {label: {"simulation": {...}, "jacobian": {...}}}."""
    from sklearn_pnlss.statespace.model_base import Segment

    with open(models_path, "rb") as f:
        models = pickle.load(f)
    out = {}
    for label, model, U in models:
        x0 = np.zeros(model.n_states)
        seg = Segment(U=U, Y=np.zeros((U.shape[0], model.C.shape[0])), n_skip=0)
        calls = {"simulation": lambda m=model: m._run(U, x0), "jacobian": lambda m=model, s=seg: m.segment_jacobian(s)}
        row = {"n_params": int(model.n_params)}
        for kind, call in calls.items():
            call()  # compiled or loaded from the cache before timing
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                call()
                times.append(time.perf_counter() - t0)
            row[kind] = {"min_ns_per_sample": min(times) / U.shape[0] * 1e9,
                         "median_ns_per_sample": statistics.median(times) / U.shape[0] * 1e9}
        out[label] = row
    return out


# cProfile entries summed into each part of a fit (their own time; the
# runaway checks' with what they call)
FIT_PARTS = {"jacobian kernel": ("decoupled_jacobian", False), "normal equations": ("chunk_sums", False),
             "simulation kernel": ("decoupled_simulate", False), "runaway checks": ("runs_away", True),
             "eigendecomposition": ("eigh", False)}


def fit_profile(n_branches, degree):
    """Seconds of one grid fit (five starts, 100 iterations, validation on
    a third realisation, one BLAS thread) by part, from cProfile."""
    import cProfile
    import pstats

    from threadpoolctl import threadpool_limits

    from sklearn_pnlss import DecoupledPNLSSRegressor, PNLSSRegressor
    from sklearn_pnlss.datasets import make_bouc_wen

    data = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, random_state=0)
    X, y = data.X_train[:2], data.y_train[:2]
    X_val, y_val = data.X_train[2:, PERIOD:], data.y_train[2:, PERIOD:]
    with warnings.catch_warnings(), threadpool_limits(1):
        warnings.simplefilter("ignore")
        start = PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=PERIOD, max_iter=200).fit(X, y)

        X_start = start.transform(X)  # the signals with the start attached, as the grid's cached stage gives them

        def fit(d):
            DecoupledPNLSSRegressor(3, n_branches=n_branches, degree=d, period=PERIOD, n_init=5, n_jobs=1,
                                    max_iter=100, random_state=0).fit(X_start, y, X_val=X_val, y_val=y_val)

        fit(degree - 1)  # kernels compiled and the CPD of this branch count kept, as in the grid
        profile = cProfile.Profile()
        t0 = time.perf_counter()
        profile.enable()
        fit(degree)
        profile.disable()
        total = time.perf_counter() - t0
    parts = dict.fromkeys(FIT_PARTS, 0.0)
    for (_, _, name), (_, _, own, cumulative, _) in pstats.Stats(profile).stats.items():
        for part, (function, with_callees) in FIT_PARTS.items():
            if name == function:
                parts[part] += cumulative if with_callees else own
    parts["rest"] = total - sum(parts.values())
    return {"n_branches": n_branches, "degree": degree, "fit_s": total, "parts_s": parts}


def measure_in(checkout, models_path, repeat):
    """:func:`measure` in a fresh interpreter importing ``checkout``'s code."""
    with tempfile.TemporaryDirectory() as tmp:
        result = Path(tmp) / "times.json"
        subprocess.run([sys.executable, str(Path(__file__).resolve()), "--measure", str(models_path), "--repeat",
                        str(repeat), "--output", str(result)], env=dict(os.environ, PYTHONPATH=str(checkout)),
                       cwd=checkout, check=True)
        return json.loads(result.read_text())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=41)
    parser.add_argument("--baseline", help="checkout of an earlier commit whose kernels are timed in turn")
    parser.add_argument("--baseline-rounds", type=int, default=3)
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT))
    parser.add_argument("--fit-profile", action="store_true", help="where one grid fit's time goes")
    parser.add_argument("--fit-profile-model", type=int, nargs=2, default=[6, 11], metavar=("BRANCHES", "DEGREE"))
    parser.add_argument("--measure", help=argparse.SUPPRESS)  # internal: time the pickled models, write JSON
    args = parser.parse_args(argv)
    if args.measure:
        Path(args.output).write_text(json.dumps(measure(args.measure, args.repeat)))
        return

    with tempfile.TemporaryDirectory() as tmp:
        models_path = Path(tmp) / "models.pkl"
        fit_models(models_path)
        rounds = []
        for _ in range(args.baseline_rounds if args.baseline else 1):
            ours = measure_in(REPO, models_path, args.repeat)
            theirs = measure_in(Path(args.baseline).resolve(), models_path, args.repeat) if args.baseline else None
            rounds.append({"ours": ours, "baseline": theirs})

    results = header()
    table = {}
    for label in rounds[0]["ours"]:
        row = {"n_params": rounds[0]["ours"][label]["n_params"]}
        for kind in ("simulation", "jacobian"):
            ours = [r["ours"][label][kind]["min_ns_per_sample"] for r in rounds]
            row[kind] = {"min_ns_per_sample": statistics.median(ours)}
            line = f"{label:32s} {kind:10s} {row[kind]['min_ns_per_sample']:8.1f} ns a sample"
            if args.baseline:
                theirs = [r["baseline"][label][kind]["min_ns_per_sample"] for r in rounds]
                ratio = statistics.median(o / t for o, t in zip(ours, theirs, strict=True))
                row[kind].update(baseline_min_ns_per_sample=statistics.median(theirs), ratio_median=ratio)
                line += f"  (baseline {row[kind]['baseline_min_ns_per_sample']:8.1f}, ratio {ratio:.2f})"
            print(line)
        table[label] = row
    profile = fit_profile(*args.fit_profile_model) if args.fit_profile else None
    if profile:
        print(f"one grid fit, {profile['n_branches']} branches of degree {profile['degree']}: "
              f"{profile['fit_s']:.1f} s = " + ", ".join(f"{k} {v:.1f}" for k, v in profile["parts_s"].items()))
    results.update({"commit": commit_of(), "period": PERIOD, "repeat": args.repeat, "kernels": table,
                    "rounds": rounds, "fit_profile": profile,
                    "baseline_commit": commit_of(args.baseline) if args.baseline else None})
    write_results(results, args.output)


if __name__ == "__main__":
    main()
