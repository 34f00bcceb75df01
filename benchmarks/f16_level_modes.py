"""How the F-16's modes move with the excitation level: a linear model of
each level on its own, and which law of the force amplitude follows the
modes' frequencies.

A term ``z |z|`` in a restoring force (friction, a clearance, the microslip
of a bolted joint) shifts a mode's frequency in proportion to the vibration
amplitude; a term ``z**3`` in proportion to its square. This script fits
``BLAEstimator(10)`` to the full multisine of each level 1 to 7 (2-15 Hz),
lists every mode's frequency and damping ratio per level, and fits each
mode's frequency over the seven levels by ``a + b F`` and by ``a + b F**2``
(``F``: the level's force rms), printing the rms misfit of both laws; writes
``results/f16_level_modes.json``.

    python benchmarks/f16_level_modes.py [--data PATH]
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402

from sklearn_pnlss import BLAEstimator  # noqa: E402
from sklearn_pnlss.datasets import load_f16  # noqa: E402

LEVELS = tuple(range(1, 8))
FS = 400.0


def modes(model):
    """Frequencies (Hz) and damping ratios of a fitted discrete-time model's
    poles, one per complex pair, by frequency."""
    s = np.log(np.linalg.eigvals(model.A_).astype(complex)) * FS
    s = s[s.imag > 0]
    s = s[np.argsort(s.imag)]
    return s.imag / (2 * np.pi), -s.real / np.abs(s)


def misfit(force, frequencies, power):
    """Rms residual (Hz) of the least-squares fit a + b force**power."""
    design = np.column_stack([np.ones_like(force), force**power])
    coef = np.linalg.lstsq(design, frequencies, rcond=None)[0]
    return float(np.sqrt(np.mean((design @ coef - frequencies) ** 2)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "f16"))
    args = parser.parse_args(argv)
    force, freqs, damping = [], [], []
    for level in LEVELS:
        d = load_f16(args.data, level=level, validation_level=None)
        f, z = modes(BLAEstimator(10, period=8192, fs=FS).fit(d.X, d.y))
        force.append(float(np.sqrt(np.mean(d.X**2))))
        freqs.append(f)
        damping.append(z)
        print(f"level {level} ({force[-1]:5.1f} N rms): "
              + "  ".join(f"{a:6.2f} Hz {100 * b:4.1f} %" for a, b in zip(f, z)), flush=True)
    force, freqs = np.array(force), np.array(freqs)
    laws = [{"mode_hz_level_1": float(freqs[0, k]), "misfit_linear_hz": misfit(force, freqs[:, k], 1),
             "misfit_quadratic_hz": misfit(force, freqs[:, k], 2)} for k in range(freqs.shape[1])]
    for law in laws:
        print(f"mode {law['mode_hz_level_1']:5.2f} Hz: rms misfit over the levels of a + b F "
              f"{law['misfit_linear_hz']:.4f} Hz, of a + b F^2 {law['misfit_quadratic_hz']:.4f} Hz")
    write_results({**header(), "levels": list(LEVELS), "force_rms_n": force.tolist(),
                   "frequencies_hz": freqs.tolist(), "damping_ratios": np.array(damping).tolist(),
                   "frequency_laws": laws}, RESULTS / "f16_level_modes.json")


if __name__ == "__main__":
    main()
