"""Where a connection's force enters, read off the content above the
excited band, on the simulated structures of family s (issue 38).

Draws the structures of ``gap_structures.py`` (chains of 2-5 masses and
two-storey frames, one element at one joint, accelerometers at the joint's
points and the driving point, 1-80 Hz multisines at 200 Hz, 1 % noise) and
reads each case's training records with
:func:`sklearn_pnlss.gap.connections.entry.read_entry` alone: no nominal,
no fit. Counts, per element, the cases read at the right place, at a wrong
one, and not read; a case without an element must not be read. The seeds
default to 7000 on, which no threshold of the reading was set on (those
were set on 3000-3015 and 5000-5009). Writes ``results/gap_entry.json``.

    python benchmarks/gap_entry.py [--seeds 24] [--first-seed 7000]
"""
import argparse
import sys
import time
import warnings
from itertools import combinations
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, write_results  # noqa: E402
from gap_structures import EFFECTS, FS, PERIOD, make_case  # noqa: E402

from sklearn_pnlss.gap.connections.entry import PAIR_MARGIN, SNR_DB, read_entry  # noqa: E402
from sklearn_pnlss.gap.connections.spectra import PeriodSpectra  # noqa: E402

BAND_TOP = 80.0  # the multisine's top line, Hz


def read_case(effect, seed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        case = make_case(effect, "exact", seed)
    points = [p for p, _ in case["sensors"]]
    spectra = PeriodSpectra.from_signals(case["X"], case["Y"], period=PERIOD, fs=FS)
    start = time.perf_counter()
    reading = read_entry(spectra, case["sensors"], BAND_TOP, [*combinations(points, 2), *((p, None) for p in points)])
    seconds = time.perf_counter() - start
    if reading.place is None:
        outcome = "not read"
    else:
        outcome = "right" if effect is not None and set(reading.place) == set(case["joint"]) else "wrong"
    return dict(effect=effect, seed=seed, joint=case["joint"], sensors=points, n_dof=case["n_dof"],
                place=reading.place, snr_db=round(reading.snr_db, 1), direction=np.round(reading.direction, 3).tolist(),
                pair_gain=reading.pair_gain, outcome=outcome, seconds=seconds)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=24)
    parser.add_argument("--first-seed", type=int, default=7000)
    args = parser.parse_args(argv)
    rows, summary = [], {}
    for effect in EFFECTS:
        counts = summary.setdefault(str(effect), {"right": 0, "wrong": 0, "not read": 0})
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            row = read_case(effect, seed)
            rows.append(row)
            counts[row["outcome"]] += 1
            if row["outcome"] == "wrong" or (effect is None and row["outcome"] != "not read"):
                print(f"  {effect} seed {seed}: joint {row['joint']} read {row['place']} ({row['snr_db']} dB)")
        print(f"{str(effect):<18} {counts}", flush=True)
    strong = [r for r in rows if r["effect"] is not None and r["snr_db"] >= SNR_DB and r["pair_gain"] is not None]
    gains = dict(grounded_max=max(r["pair_gain"] for r in strong if r["joint"][1] is None),
                 pair_min=min(r["pair_gain"] for r in strong if r["joint"][1] is not None),
                 pair_margin=PAIR_MARGIN)
    print(f"what the best pair adds: at most {gains['grounded_max']:.3f} for a grounded force, at least "
          f"{gains['pair_min']:.3f} for a pair (PAIR_MARGIN {PAIR_MARGIN})")
    out = dict(header(), args=vars(args), summary=summary, pair_gain=gains,
               median_read_seconds=float(np.median([r["seconds"] for r in rows])), rows=rows)
    write_results(out, RESULTS / "gap_entry.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
