"""How the F-16's modes move with the excitation level, in the data and in
a fitted model, and where the model's error of each level lies.

A term ``z |z|`` in a restoring force (friction, a clearance, the microslip
of a bolted joint) shifts a mode's frequency in proportion to the vibration
amplitude; a term ``z**3`` in proportion to its square. This script fits
``BLAEstimator(10)`` to the full multisine of each level 1 to 7 (2-15 Hz,
:func:`sklearn_pnlss.level_modes.modes_by_level`), lists every mode's
frequency and damping ratio per level, and fits each mode's frequency over
the seven levels by ``a + b F`` and by ``a + b F**2`` (``F``: the level's
force rms), printing the rms misfit of both laws.

With ``--model`` it also fits the benchmark's best model of the band (the
18-state decoupled model of three branches of degree 5 in signed powers,
on levels 1, 3, 5 and 7 as ``bench_f16.py`` does, about 3 minutes), gives
the modes of its simulation of every level beside the measured ones, and
splits each level's error in the band over the modes (bands between the
level-1 frequencies): a level between fitted ones is missed where the
model's amplitude dependence of a lightly damped mode is off. Writes
``results/f16_level_modes.json``.

    python benchmarks/f16_level_modes.py [--data PATH] [--model]
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import REPO, RESULTS, header, write_results  # noqa: E402

from bench_f16 import TRAIN_LEVELS, decoupled_estimator  # noqa: E402

from sklearn_pnlss import BLAEstimator  # noqa: E402
from sklearn_pnlss.datasets import load_f16  # noqa: E402
from sklearn_pnlss.level_modes import modes_by_level  # noqa: E402
from sklearn_pnlss.metrics import nrmse_by_band  # noqa: E402

LEVELS = tuple(range(1, 8))
FS, PERIOD, BAND_HZ = 400.0, 8192, (2.0, 15.5)


def fit_best_model(data):
    """The 18-state decoupled model in signed powers of degree 5, fitted by
    bench_f16.py's protocol (``--decoupled 3:5:18 --branch-basis
    signed_powers``, draw 0): the estimation levels stacked, each level's
    error relative to its power."""
    X = np.concatenate([data[lv].X for lv in TRAIN_LEVELS])
    y = np.concatenate([data[lv].y for lv in TRAIN_LEVELS])
    start = BLAEstimator(18, period=PERIOD, fs=FS).fit(X, y)
    return decoupled_estimator(18, 3, 5, branch_basis="signed_powers").fit(start.transform(X), y)


def misfit(force, frequencies, power):
    """Rms residual (Hz) of the least-squares fit a + b force**power."""
    design = np.column_stack([np.ones_like(force), force**power])
    coef = np.linalg.lstsq(design, frequencies, rcond=None)[0]
    return float(np.sqrt(np.mean((design @ coef - frequencies) ** 2)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "f16"))
    parser.add_argument("--model", action="store_true",
                        help="also the best model of the band: its modes per level and its error per mode")
    args = parser.parse_args(argv)
    data = {lv: load_f16(args.data, level=lv, validation_level=None) for lv in LEVELS}
    model = fit_best_model(data) if args.model else None
    modes = modes_by_level([data[lv].X for lv in LEVELS], [data[lv].y for lv in LEVELS], model,
                           n_states=10, period=PERIOD, fs=FS)
    force, freqs = modes.input_rms, modes.frequencies
    for i, level in enumerate(LEVELS):
        print(f"level {level} ({force[i]:5.1f} N rms): "
              + "  ".join(f"{a:6.3f} Hz {100 * b:4.2f} %" for a, b in zip(freqs[i], modes.damping[i]))
              + ("" if model is None else "\n     model:        " + "  ".join(
                  f"{a:6.3f} Hz {100 * b:4.2f} %" for a, b in zip(modes.model_frequencies[i], modes.model_damping[i]))),
              flush=True)
    laws = [{"mode_hz_level_1": float(freqs[0, k]), "misfit_linear_hz": misfit(force, freqs[:, k], 1),
             "misfit_quadratic_hz": misfit(force, freqs[:, k], 2)} for k in range(freqs.shape[1])]
    for law in laws:
        print(f"mode {law['mode_hz_level_1']:5.2f} Hz: rms misfit over the levels of a + b F "
              f"{law['misfit_linear_hz']:.4f} Hz, of a + b F^2 {law['misfit_quadratic_hz']:.4f} Hz")
    results = {**header(), "levels": list(LEVELS), "force_rms_n": force.tolist(), "frequencies_hz": freqs.tolist(),
               "damping_ratios": modes.damping.tolist(), "frequency_laws": laws}
    if model is not None:
        results["model"] = {"estimator": repr(model), "train_levels": list(TRAIN_LEVELS),
                            **model_errors(model, data, freqs[0]),
                            "frequencies_hz": modes.model_frequencies.tolist(),
                            "damping_ratios": modes.model_damping.tolist()}
    write_results(results, RESULTS / "f16_level_modes.json")


def model_errors(model, data, mode_hz):
    """Each level's NRMSE in the band and its split over the modes: bands
    from 2 Hz to 15.5 Hz cut halfway between the level-1 frequencies
    ``mode_hz``; the squares of a level's split add up to its square in the
    band."""
    edges = [BAND_HZ[0], *((mode_hz[:-1] + mode_hz[1:]) / 2), BAND_HZ[1]]
    in_band, by_mode = {}, {}
    for lv in LEVELS:
        pred = model.predict(data[lv].X)
        in_band[str(lv)] = nrmse_by_band(data[lv].y, pred, fs=FS, edges=BAND_HZ)[0].tolist()
        by_mode[str(lv)] = nrmse_by_band(data[lv].y, pred, fs=FS, edges=edges).tolist()
        print(f"level {lv}: NRMSE in the band " + "/".join(f"{v:.3f}" for v in in_band[str(lv)]) + "; at the modes "
              + "  ".join(f"{f:.2f} Hz " + "/".join(f"{v:.3f}" for v in row) for f, row in zip(mode_hz, by_mode[str(lv)])))
    return {"band_edges_hz": [float(e) for e in edges], "nrmse_in_band": in_band, "nrmse_by_mode": by_mode}


if __name__ == "__main__":
    main()
