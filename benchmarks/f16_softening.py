"""Which place of the F-16's sensors its level dependence asks for, mode by
mode (issue 38).

A joint whose stiffness k drops by dk between two levels lowers each mode's
squared angular frequency by dk psi_r**2 (mass-normalised modes, to first
order in the change; the two levels' modes matched by their order), and a
damping it adds raises each mode's 2 zeta_r omega_r by dc psi_r**2, where
psi_r is the mode's share of the joint's relative motion: phi_a - phi_b
for a joint between the points a and b, phi_a to the ground. So the
pattern of the modes' changes from the lowest to the highest estimation
level (the modal models read off levels 1 and 7, 2-15 Hz) is the square of
the joint's shape, whatever its law. This script fits each sensor place's
psi**2 to that pattern (one non-negative factor) and prints the share of the
pattern it explains, for the stiffness and the damping; writes
``results/f16_softening.json``.

    python benchmarks/f16_softening.py [--data PATH]
"""
import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402

from sklearn_pnlss.datasets import load_f16  # noqa: E402
from sklearn_pnlss.gap import modal_nominal  # noqa: E402

POINTS = ["drive", "wing", "payload"]
LEVELS = (1, 7)  # the lowest and highest estimation levels
N_MODES = 6  # the modes both levels' fits tell apart in 2-15 Hz


def explained(pattern, shape_squared):
    """Share of ``pattern`` that ``c * shape_squared`` (c >= 0, least
    squares) explains: 1 - |pattern - c s|^2 / |pattern|^2."""
    c = max(float(shape_squared @ pattern) / float(shape_squared @ shape_squared), 0.0)
    return 1.0 - float(np.sum((pattern - c * shape_squared) ** 2) / np.sum(pattern**2))


def softening_pattern(data_dir):
    """The modes' stiffness loss and damping gain from the lowest to the
    highest estimation level, and each sensor place's share of them."""
    fits = {}
    for level in LEVELS:
        d = load_f16(data_dir, level=level, validation_level=None)
        fits[level] = modal_nominal(d.X, d.y, fs=400.0, points=POINTS, driving_point="drive", period=8192,
                                    f_band=(2.0, 15.0), n_modes=N_MODES)
    low, high = (fits[level] for level in LEVELS)
    w_low = 2 * np.pi * low.modal_fit_.frequencies
    w_high = 2 * np.pi * high.modal_fit_.frequencies
    stiffness_loss = w_low**2 - w_high**2
    damping_gain = 2 * high.modal_fit_.damping_ratios * w_high - 2 * low.modal_fit_.damping_ratios * w_low
    rows = []
    for a, b in [(a, None) for a in POINTS] + list(itertools.combinations(POINTS, 2)):
        psi2 = low.direction(a, b)[low.coupled] ** 2
        rows.append({"place": [a, b], "stiffness_explained": explained(stiffness_loss, psi2),
                     "damping_explained": explained(damping_gain, psi2)})
    shapes = {a: low.direction(a)[low.coupled].tolist() for a in POINTS}  # mass-normalised, level 1
    return {"levels": list(LEVELS), "frequencies_hz": low.modal_fit_.frequencies.tolist(), "shapes": shapes,
            "stiffness_loss": stiffness_loss.tolist(), "damping_gain": damping_gain.tolist(), "places": rows}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "f16"))
    args = parser.parse_args(argv)
    pattern = softening_pattern(args.data)
    print(f"modes {np.round(pattern['frequencies_hz'], 2)} Hz at level {LEVELS[0]}; from level {LEVELS[0]} to "
          f"{LEVELS[1]}: stiffness loss {np.round(pattern['stiffness_loss'], 1)} (rad/s)^2, damping gain "
          f"{np.round(pattern['damping_gain'], 3)} rad/s")
    for row in pattern["places"]:
        a, b = row["place"]
        print(f"  {a + '-' + (b or 'ground'):<16} explains {row['stiffness_explained']:.3f} of the stiffness loss, "
              f"{row['damping_explained']:.3f} of the damping gain")
    write_results({**header(), **pattern}, RESULTS / "f16_softening.json")


if __name__ == "__main__":
    main()
