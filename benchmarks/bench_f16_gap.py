"""The structural gap diagnosis on the F-16 ground vibration test (issue 38).

The nominal is the modal model read off level 1 (2-15 Hz, six modes and two
residual ones); the diagnosis trains on the benchmark's estimation levels 1,
3, 5 and 7 and is read on its test levels 2, 4 and 6.  Prints the locator's
places, every simulated law, the verdict and the error per level and
output before and after, and the locator's ranking with each connection's
share of each mode fitted (``participation="free"``, the relative motions
read down to 10 dB and at the default 20 dB); writes
``results/f16_gap.json``.

``--no-ground`` leaves the places to the ground out (what an engineer
knows who knows the payload hangs from the wing, not from the floor): the
pairs of sensed points only; writes ``results/f16_gap_pairs.json`` (no
free-participation reading).

    python benchmarks/bench_f16_gap.py [--data PATH] [--no-ground]
"""
import argparse
import sys
import time
from itertools import combinations
from pathlib import Path

import numpy as np
from _bench_utils import REPO, RESULTS, header, write_results

from sklearn_pnlss.datasets import load_f16
from sklearn_pnlss.gap import ConnectionLocator, StructuralGapDiagnosis, modal_nominal

POINTS = ["drive", "wing", "payload"]
SENSORS = [(p, "acceleration") for p in POINTS]
TRAIN, TEST = (1, 3, 5, 7), (2, 4, 6)
# The free-participation reading's mask: the relative motions read down to
# 10 dB over their noise (the locator's default is 20 dB).
FREE_MOTION_SNR = 10.0


def free_participation(nominal, train, test):
    """The locator with each connection's share of each mode fitted
    (``participation="free"``): every place's best law, what it explains on
    the training and validation levels, and its share of each mode beside
    the nominal's ``phi_a - phi_b``."""
    rows = []
    for snr in (FREE_MOTION_SNR, None):
        kwargs = {} if snr is None else {"motion_snr": snr}
        loc = ConnectionLocator(nominal, fs=400.0, period=8192, inputs=["drive"], sensors=SENSORS,
                                f_band=(2.0, 15.0), participation="free", **kwargs).fit(*train)
        for c in loc.ranking_:
            rows.append(dict(motion_snr=loc.motion_snr, place=c.place, law=c.law.name, explained=c.explained,
                             test_explained=loc.explained(*test, c)[1].tolist(),
                             participation=c.participation.tolist(),
                             nominal_participation=nominal.direction(*c.place)[nominal.coupled].tolist()))
            print(f"  free participation, {10 * np.log10(loc.motion_snr):.0f} dB: {c.law.name:<20} at "
                  f"{c.place_name:<16} explains {c.explained:.3f}, on levels {TEST} "
                  + "/".join(f"{v:.3f}" for v in rows[-1]["test_explained"]))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "f16"))
    parser.add_argument("--no-ground", action="store_true", help="places between sensed points only")
    args = parser.parse_args(argv)
    places = list(combinations(POINTS, 2)) if args.no_ground else None
    data = {level: load_f16(args.data, level=level, validation_level=None) for level in TRAIN + TEST}
    start = time.perf_counter()
    nominal = modal_nominal(data[1].X, data[1].y, fs=400.0, points=POINTS, driving_point="drive", period=8192,
                            f_band=(2.0, 15.0))
    train = [data[k].X[0] for k in TRAIN], [data[k].y[0] for k in TRAIN]
    test = [data[k].X[0] for k in TEST], [data[k].y[0] for k in TEST]
    gap = StructuralGapDiagnosis(nominal, fs=400.0, period=8192, inputs=["drive"], sensors=SENSORS,
                                 f_band=(2.0, 15.0), places=places)
    gap.fit(*train)
    fit_seconds = time.perf_counter() - start
    report = gap.report(*test)
    seconds = time.perf_counter() - start
    print(report)
    free = [] if args.no_ground else free_participation(nominal, train, test)
    fits = [dict(place=f.place, law=f.law.name, train_error=f.train_error.round(4).tolist(),
                 seconds=round(f.seconds, 1), simulations=f.n_simulations) for f in gap.fits_]
    for f in fits:
        print(f"  {f['law']:<20} at {str(f['place']):<20} training error {f['train_error']}  {f['seconds']} s")
    out = dict(header(), seconds=seconds, fit_seconds=fit_seconds, n_modes=int(nominal.modal_fit_.frequencies.size),
               effect_found=report.effect_found, place=report.place, law=report.law,
               parameters={k: float(v) for k, v in report.parameters.items()},
               test_levels=TEST, nominal_error=report.nominal_error.tolist(),
               connection_error=report.connection_error.tolist(), linear_error=report.linear_error.tolist(),
               closure=report.closure.tolist(), left_over_noise_db=report.left_over_noise_db.tolist(),
               nominal_nrmse=report.nominal_nrmse.tolist(), connection_nrmse=report.connection_nrmse.tolist(),
               nominal_train_error=gap.nominal_train_error_.tolist(),
               ranking=[dict(place=c.place, law=c.law.name, explained=c.explained,
                             nonlinear_gain=c.nonlinear_gain) for c in report.ranking],
               fits=fits, free_participation=free,
               entry=dict(place=gap.entry_.place, snr_db=gap.entry_.snr_db, direction=gap.entry_.direction.tolist(),
                          band=gap.entry_.band, explained=[dict(place=p, share=v)
                                                           for p, v in gap.entry_.explained.items()]))
    print(f"{seconds:.0f} s in all")
    write_results(out, RESULTS / ("f16_gap_pairs.json" if args.no_ground else "f16_gap.json"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
