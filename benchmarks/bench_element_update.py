"""The model update of a lumped nominal (``recalibrate=True`` of the
structural gap diagnosis, :mod:`sklearn_pnlss.gap.connections.update`) on
drawn structures 10-30 % off, with and without its first stage (the
natural frequencies fitted before the response).

Each draw is a structure of ``gap_structures.py`` (a chain of 2-5 masses
or a two-storey frame), its nominal every mass and spring 10-30 % off,
the driving point and up to two more points sensed by accelerometers,
the measured response the true one with 1 % noise.  A draw is counted
stuck where the updated response misses the measured one by more than
twice the noise.  Writes ``results/element_update.json``.

    python benchmarks/bench_element_update.py --draws 60
"""
import argparse
import json
import sys
import time
from unittest import mock

import numpy as np
from _bench_utils import RESULTS, header
from gap_structures import FS, PERIOD, draw_structure, stiffness_matrix

from sklearn_pnlss.gap.connections import update
from sklearn_pnlss.physics import Structure

NOISE = 0.01


def draw(seed):
    rng = np.random.default_rng(seed)
    points, M, C, K, joints, masses, springs = draw_structure(rng)
    off = lambda a: a * (1 + rng.choice([-1, 1], a.size) * rng.uniform(0.1, 0.3, a.size))  # noqa: E731
    nominal = Structure(np.diag(off(masses)), C, stiffness_matrix(points, joints, off(springs)), points=points)
    drive = points[int(rng.integers(len(points)))]
    sensors = [(p, "acceleration") for p in dict.fromkeys([drive] + points[:2])]
    freqs = np.arange(20, 1640, 2) * FS / PERIOD  # the family's band, 1-80 Hz
    H = Structure(M, C, K, points=points).frequency_response(freqs, inputs=[drive], sensors=sensors)
    H = H * (1 + NOISE * rng.standard_normal(H.shape))
    return nominal, freqs, H, [drive], sensors


def misfit(structure, freqs, H, inputs, sensors, weights):
    G = structure.frequency_response(freqs, inputs=inputs, sensors=sensors)
    w = weights[None, :, None]
    return float(np.sqrt(np.mean(np.abs((G - H) * w) ** 2) / np.mean(np.abs(H * w) ** 2)))


def run(seed, frequencies_first):
    nominal, freqs, H, inputs, sensors = draw(seed)
    weights = 1.0 / np.sqrt(np.mean(np.abs(H) ** 2, axis=(0, 2)))
    start = time.perf_counter()
    if frequencies_first:
        updated, _ = update.updated_elements(nominal, freqs, H, weights, fs=FS, inputs=inputs, sensors=sensors)
    else:  # the response alone: no measured frequencies, so no first stage
        with mock.patch.object(update, "_measured_frequencies", return_value=None):
            updated, _ = update.updated_elements(nominal, freqs, H, weights, fs=FS, inputs=inputs, sensors=sensors)
    return dict(seed=seed, n_dof=nominal.n_dof, before=misfit(nominal, freqs, H, inputs, sensors, weights),
                after=misfit(updated, freqs, H, inputs, sensors, weights), seconds=time.perf_counter() - start)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=60)
    args = parser.parse_args(argv)
    out = dict(header(), draws=args.draws, noise=NOISE)
    for label, first in (("frequencies_then_response", True), ("response_alone", False)):
        rows = [run(seed, first) for seed in range(args.draws)]
        stuck = [r["seed"] for r in rows if r["after"] > 2 * NOISE]
        out[label] = dict(stuck=len(stuck), stuck_seeds=stuck,
                          median_after=float(np.median([r["after"] for r in rows])),
                          median_seconds=float(np.median([r["seconds"] for r in rows])), rows=rows)
        print(f"{label:<26} stuck in {len(stuck)} of {args.draws} draws {stuck}; median misfit "
              f"{out[label]['median_after']:.4f} (noise {NOISE}), {out[label]['median_seconds']:.2f} s per update",
              flush=True)
    path = RESULTS / "element_update.json"
    path.write_text(json.dumps(out, indent=1, default=str))
    print(f"written {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
