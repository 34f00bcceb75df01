"""Where the locator places a withheld connection, with each mode's share of
a connection taken from the nominal or fitted with its law (issue 38).

The effect cases of ``gap_structures.py`` (family s: chains and frames of
2-5 masses, one element at one joint, accelerometers, 1 % noise), with the
exact nominal and with the modes read off the lowest training record
(``modal_nominal``; the diagnosis also tries the highest and keeps the
better, this script does not). Each case is located three ways:
``ConnectionLocator`` as the diagnosis runs it (``participation=
"nominal"``), with ``participation="free"`` at the default 20 dB mask, and
free at 10 dB (the F-16's reading, ``bench_f16_gap.py``). Scored on the
locator's leading place only (no simulation, no law): how often it is the
withheld joint. Writes ``results/gap_locator_participation.json``.

    python benchmarks/gap_locator_participation.py [--seeds 4]
"""
import argparse
import json
import sys
import time

import numpy as np
from _bench_utils import RESULTS, header
from gap_structures import EFFECTS, FS, PERIOD, make_case

from sklearn_pnlss.gap import ConnectionLocator, modal_nominal

READINGS = {"nominal": {}, "free, 20 dB": {"participation": "free"},
            "free, 10 dB": {"participation": "free", "motion_snr": 10.0}}


def lowest_level_modes(case):
    """The modes read off the case's lowest training record."""
    lowest = int(np.argmin([np.sqrt(np.mean(x**2)) for x in case["X"]]))
    return modal_nominal(case["X"][lowest], case["Y"][lowest], fs=FS, points=[p for p, _ in case["sensors"]],
                         driving_point=case["drive"], period=PERIOD)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=4)
    args = parser.parse_args(argv)
    rows = []
    for nominal_kind in ("exact", "modal"):
        for effect in EFFECTS:
            if effect is None:
                continue
            for seed in range(args.seeds):
                case = make_case(effect, nominal_kind, 1000 * EFFECTS.index(effect) + seed)
                nominal = lowest_level_modes(case) if case["nominal"] == "modal" else case["nominal"]
                row = dict(nominal=nominal_kind, effect=effect, seed=seed, joint=case["joint"], got={})
                for name, kwargs in READINGS.items():
                    start = time.perf_counter()
                    loc = ConnectionLocator(nominal, fs=FS, period=PERIOD, inputs=[case["drive"]],
                                            sensors=case["sensors"], **kwargs).fit(case["X"], case["Y"])
                    row["got"][name] = dict(place=loc.best_.place, law=loc.best_.law.name,
                                            right=set(loc.best_.place) == set(case["joint"]),
                                            seconds=time.perf_counter() - start)
                rows.append(row)
                print(f"{nominal_kind:<6} {effect:<18} seed {seed} joint {case['joint']}: "
                      + "  ".join(f"{name} {'right' if g['right'] else 'WRONG ' + str(g['place'])}"
                                  for name, g in row["got"].items()), flush=True)
    summary = {kind: {name: int(sum(r["got"][name]["right"] for r in rows if r["nominal"] == kind))
                      for name in READINGS} for kind in ("exact", "modal")}
    summary["cases_per_nominal"] = len(rows) // 2
    print(json.dumps(summary, indent=1))
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "gap_locator_participation.json"
    path.write_text(json.dumps(dict(header(), summary=summary, rows=rows), indent=1, default=str))
    print(f"written {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
