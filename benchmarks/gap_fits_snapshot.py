"""Every fit of seven gap diagnoses, to tell a refactor that changes nothing
from one that changes the numbers.

One case per family of ``gap_withheld.py`` (and two in family d), each a
whole diagnosis (``n_jobs=2``): the fitted candidates' (and the forward
selection's combinations') ``theta``, training errors and simulation counts, the ranking on validation and the verdict.
``--write`` stores them in ``results/gap_fits_snapshot.json``; without it
the present code's fits are compared with that file and every difference
is printed (exact equality: a pure refactor keeps every bit; a change of
arithmetic shows as relative differences of the order of 1e-12, and the
verdicts must stay).  About five minutes on 2 cores.

    python benchmarks/gap_fits_snapshot.py --write   # on the code to compare with
    python benchmarks/gap_fits_snapshot.py           # after the change
"""
import argparse
import json
import time

import numpy as np
from _bench_utils import RESULTS, header

import gap_withheld as cases
from sklearn_pnlss.gap import GapDiagnosis

# (family, true effect, strength, seed)
CASES = [("e", "cubic_stiffness", 0, 0), ("e", None, 0, 0), ("d", "backlash", 0, 1), ("d", "input_delay", 0, 0),
         ("b", "second_mode", 0, 0), ("c", "hysteresis", 0, 0), ("a", "recalibration", 0, 1)]
OUT = RESULTS / "gap_fits_snapshot.json"


def snapshot(family, name, strength, seed):
    t0 = time.perf_counter()
    u, y, u_val, y_val, _, period, _ = cases.make_data(cases.CASES[name][strength], seed, family,
                                                       cases._layout(family, name, seed))
    nominal = cases._nominal(family, u, y, period, seed)
    diagnosis = GapDiagnosis(nominal, fs=cases.FS, period=period, n_jobs=2, random_state=seed).fit(u, y)
    report = diagnosis.report(u_val, y_val)
    return dict(best=report.best_effect, delay_s=None if diagnosis.delay_ is None else diagnosis.delay_.delay_s,
                fits={f.effect.name: dict(theta=[float(t) for t in f.theta], train_mse=f.train_mse,
                                          n_evaluations=f.n_evaluations, refined=f.refined)
                      for f in diagnosis.fits_ + diagnosis.combinations_},
                ranking=[[r.name, r.gap_after_db] for r in report.ranking], seconds=time.perf_counter() - t0)


def differences(old, new):
    """Lines naming each difference of ``new`` from ``old``, and the worst
    relative difference of a fitted parameter or training error."""
    lines, worst = [], 0.0
    for key, was in old.items():
        now = new[key]
        if now["best"] != was["best"]:
            lines.append(f"{key}: verdict {was['best']} -> {now['best']}")
        for name, fit in was["fits"].items():
            other = now["fits"].get(name)
            if other is None:
                lines.append(f"{key}: {name} no longer fitted")
                continue
            a = np.array(fit["theta"] + [fit["train_mse"]])
            b = np.array(other["theta"] + [other["train_mse"]])
            if a.shape != b.shape or fit["n_evaluations"] != other["n_evaluations"] or not np.array_equal(a, b):
                rel = float(np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-300))) if a.shape == b.shape else np.inf
                worst = max(worst, rel)
                lines.append(f"{key}: {name} relative difference {rel:.1e}, simulations "
                             f"{fit['n_evaluations']} -> {other['n_evaluations']}, training "
                             f"{10 * np.log10(fit['train_mse']):.2f} -> {10 * np.log10(other['train_mse']):.2f} dB")
    return lines, worst


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write", action="store_true", help="store the snapshot instead of comparing with it")
    args = parser.parse_args(argv)
    rows = {}
    for family, name, strength, seed in CASES:
        key = f"{family}/{name}/{strength}/{seed}"
        rows[key] = snapshot(family, name, strength, seed)
        print(f"{key}: {rows[key]['best']} ({rows[key]['seconds']:.1f} s)", flush=True)
    if args.write:
        OUT.write_text(json.dumps(dict(header(), commit=cases.COMMIT, cases=rows), indent=1))
        print(f"wrote {OUT}")
        return
    lines, worst = differences(json.loads(OUT.read_text())["cases"], rows)
    print("\n".join(lines) or "every fit identical")
    print(f"worst relative difference {worst:.1e}")


if __name__ == "__main__":
    main()
