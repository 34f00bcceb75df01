"""Where a gap diagnosis spends its time.

Runs withheld-effect cases of ``gap_withheld.py`` (the exact nominal, four
realisations of four steady-state periods, 2 cores) and measures, per case:

- the wall time of ``fit`` and ``report``, and of each stage of ``fit``
  (``sklearn_pnlss.gap.stages.STAGES``);
- per candidate: its simulations of the training set and its seconds (on
  its worker thread; each stage it went through summed);
- the integrator's share: seconds and steps per force element and rate,
  and nanoseconds per step;
- the black box's seconds.

Cases: an effect's name or ``null`` (the clean family's first seed),
``backlash-removed`` (its second strength, seed 501, with no backlash among
the candidates: family e's slowest case) and ``pair:STRONG+WEAK`` (family
t's pair, seed 0), e.g. ``--cases backlash-removed
pair:cubic_stiffness+coulomb_friction``.

The integrator is timed by wrapping ``Oscillator._run`` and
``Oscillator._run_tangents`` (where the code has them), so the same script
measures an older commit too:

    python benchmarks/bench_gap_time.py --label after
    git worktree add /tmp/before <commit>
    PYTHONPATH=/tmp/before python benchmarks/bench_gap_time.py --label before

Each label's rows are written to ``results/gap_time.json`` (other labels
kept), with the commit measured.
"""
import argparse
import collections
import json
import sys
import threading
import time
from pathlib import Path

import numpy as np
from _bench_utils import RESULTS, commit_of, header

import gap_withheld as gw
import sklearn_pnlss
from sklearn_pnlss.gap import GapDiagnosis, default_effects
from sklearn_pnlss.physics import oscillator

CASES = ["cubic_stiffness", "hysteresis", "null"]


class IntegratorClock:
    """Seconds and steps of every integrator run, by force elements and rate
    (thread-safe: candidates are fitted in threads)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.table = collections.defaultdict(lambda: [0.0, 0])
        self.originals = {}

    def _wrap(self, name):
        original = getattr(oscillator.Oscillator, name)
        self.originals[name] = original
        clock = self

        def timed(osc, u_fine, n_steps, h, *args, **kwargs):
            start = time.perf_counter()
            out = original(osc, u_fine, n_steps, h, *args, **kwargs)
            key = (("+".join(type(f).__name__ for f in osc.forces) or "linear")
                   + f" at {round(1 / h / gw.FS)}x" + (" with sensitivities" if name == "_run_tangents" else ""))
            with clock.lock:
                row = clock.table[key]
                row[0] += time.perf_counter() - start
                row[1] += int(n_steps)
            return out

        setattr(oscillator.Oscillator, name, timed)

    def __enter__(self):
        for name in ("_run", "_run_tangents"):
            if hasattr(oscillator.Oscillator, name):
                self._wrap(name)
        return self

    def __exit__(self, *exc):
        for name, original in self.originals.items():
            setattr(oscillator.Oscillator, name, original)

    def rows(self):
        return {k: dict(seconds=round(s, 2), steps=n, ns_per_step=round(1e9 * s / max(n, 1), 1))
                for k, (s, n) in sorted(self.table.items(), key=lambda kv: -kv[1][0])}


class BlackBoxClock:
    """Seconds of the black box's fit (wrapped where the diagnosis calls it)."""

    def __enter__(self):
        import sklearn_pnlss.gap.stages as stages

        self.module, self.original, self.seconds = stages, stages.fit_black_box, []

        def timed(*args, **kwargs):
            start = time.perf_counter()
            out = self.original(*args, **kwargs)
            self.seconds.append(time.perf_counter() - start)
            return out

        stages.fit_black_box = timed
        return self

    def __exit__(self, *exc):
        self.module.fit_black_box = self.original


class StageClock:
    """Seconds of each stage of ``GapDiagnosis.fit`` (wrapped where the
    diagnosis reads its list of stages)."""

    def __enter__(self):
        import sklearn_pnlss.gap.diagnosis as diagnosis

        self.module, self.seconds = diagnosis, {}
        self.original = getattr(diagnosis, "STAGES", None)
        if self.original is not None:
            diagnosis.STAGES = tuple(self._timed(stage) for stage in self.original)
        return self

    def _timed(self, stage):
        def timed(run):
            start = time.perf_counter()
            out = stage(run)
            self.seconds[stage.__name__] = round(time.perf_counter() - start, 1)
            return out

        return timed

    def __exit__(self, *exc):
        if self.original is not None:
            self.module.STAGES = self.original


def _case(name):
    """(truth, seed, candidates or None) of a case name (see the module's docstring)."""
    if name.startswith("pair:"):
        strong, weak = name[5:].split("+")
        (strong_name, strength), weak = next(p for p in gw.PAIRS if p[0][0] == strong and p[1] == weak)
        return gw.pair_truth((strong_name, strength), weak, 0)[0], 0, None
    if name.endswith("-removed"):
        removed = name[:-len("-removed")]
        return gw.CASES[removed][1], 501, [e for e in default_effects() if e != removed]
    return gw.CASES[None if name == "null" else name][0], 0, None


def run_case(name, n_jobs):
    truth, seed, candidates = _case(name)
    u_train, y_train, u_val, y_val, _, period, _ = gw.make_data(truth, seed, "e", None)
    with IntegratorClock() as clock, BlackBoxClock() as bb, StageClock() as stages:
        start = time.perf_counter()
        diag = GapDiagnosis(gw.NOMINAL, fs=gw.FS, period=period, effects=candidates, n_jobs=n_jobs,
                            random_state=seed).fit(u_train, y_train)
        fitted = time.perf_counter()
        report = diag.report(u_val, y_val)
        done = time.perf_counter()
    candidates = {f.effect.name: dict(seconds=round(f.seconds, 2), simulations=int(f.n_evaluations),
                                      train_db=round(10 * np.log10(f.train_mse), 2)) for f in diag.fits_}
    return dict(case=name, got=report.best_effect, seconds=round(done - start, 1), fit_s=round(fitted - start, 1),
                report_s=round(done - fitted, 1), stages=stages.seconds, black_box_s=round(sum(bb.seconds), 1),
                candidate_seconds_sum=round(sum(c["seconds"] for c in candidates.values()), 1),
                candidates=candidates, integrator=clock.rows(),
                integrator_seconds=round(sum(r["seconds"] for r in clock.rows().values()), 1))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--label", required=True, help="name of this measurement (e.g. before, after)")
    parser.add_argument("--cases", nargs="*", default=CASES)
    parser.add_argument("--n-jobs", type=int, default=2)
    args = parser.parse_args(argv)
    code = Path(sklearn_pnlss.__file__).resolve().parents[1]
    commit = commit_of(code)
    rows = []
    for name in args.cases:
        row = run_case(name, args.n_jobs)
        rows.append(row)
        print(f"{name:<18} got {str(row['got']):<18} {row['seconds']:6.1f} s (fit {row['fit_s']} s, report "
              f"{row['report_s']} s; candidates {row['candidate_seconds_sum']} s on their threads, black box "
              f"{row['black_box_s']} s, integrator {row['integrator_seconds']} s)", flush=True)
        print("    stages: " + ", ".join(f"{k} {v} s" for k, v in row["stages"].items()), flush=True)
    path = RESULTS / "gap_time.json"
    out = json.loads(path.read_text()) if path.exists() else {}
    kept = [r for r in out.get(args.label, {}).get("rows", []) if r["case"] not in args.cases]
    out[args.label] = dict(header(), commit=commit, n_jobs=args.n_jobs, rows=kept + rows)
    path.write_text(json.dumps(out, indent=1))
    print(f"written {path} ({args.label})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
