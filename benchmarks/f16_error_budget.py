"""Where the F-16 benchmark's remaining test error lies, and how far each
part would have to go for a mean test NRMSE of 0.13.

Fits the benchmark's best model (``bench_f16.py --decoupled 3:5:18
--branch-basis signed_powers --above-band``: 18 states, three branches of
degree 5 in signed powers, the gated filters above the band) for each of
``--draws`` draws of its starts, then reports:

1. **The budget.** Each test level's and output's error splits, by
   Parseval, into the part in the excited band (below 15.5 Hz) and the part
   above it. The mean NRMSE the model would reach with either part exact,
   and the in-band error (the same on every level and output) or the
   fraction of today's error above the band it would take to reach 0.13.
2. **The draws averaged.** The mean of the draws' simulations (one model:
   their state-space models side by side, each output the mean of theirs):
   how much of the error the draws share.
3. **The cost of a mode's interpolation.** A lightly damped mode's
   frequency and damping at a test level come, for any model fitted on the
   estimation levels, from how they move between those levels. Each test
   level's own linear model (``BLAEstimator(10)`` of its measurement) is
   re-simulated with one mode moved to the frequency and damping that a
   law through the estimation levels' linear models gives there (straight
   lines between the neighbouring levels, one line over the four levels,
   a parabola over them), or to the fitted model's own (its simulation's
   linear model, ``modes_by_level``). The NRMSE between the moved and the
   own simulation is what that mode's miss alone costs at that level.

Writes ``results/f16_error_budget.json``.

    python benchmarks/f16_error_budget.py [--data-dir PATH] [--draws 3] [--also-stable-at-rest]
"""
import argparse
import copy
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, write_results  # noqa: E402

from bench_f16 import BAND_EDGES, DEFAULT_DATA, TEST_LEVELS, TRAIN_LEVELS, decoupled_estimator, nrmse_of  # noqa: E402

from sklearn_pnlss import AboveBandRegressor, BLAEstimator  # noqa: E402
from sklearn_pnlss.datasets import load_f16  # noqa: E402
from sklearn_pnlss.level_modes import modes_by_level  # noqa: E402
from sklearn_pnlss.metrics import nrmse_by_band  # noqa: E402
from sklearn_pnlss.statespace.linear import modal_parameters  # noqa: E402

FS, PERIOD, TARGET = 400.0, 8192, 0.13
CUTOFF = BAND_EDGES[1]
LAWS = ("neighbours", "line", "parabola")


def fit_draw(X, y, start, seed, stable_at_rest=False):
    """The best model of the band for one draw of its starts, and the same
    with the gated filters above the band."""
    from sklearn.frozen import FrozenEstimator

    model = decoupled_estimator(18, 3, 5, branch_basis="signed_powers", random_state=seed)
    model.set_params(stable_at_rest=stable_at_rest).fit(start.transform(X), y)
    wrapped = AboveBandRegressor(FrozenEstimator(model), cutoff=CUTOFF, fs=FS).fit(X, y)
    return model, wrapped


def at_rest(model, quiet):
    """The spectral radius of the model's state equation linearised at
    rest, and the rms of what it does with no force after a tap (1 N for
    20 samples), over its last 50,000 of 250,000 samples (10 minutes), per
    output, over the rms of the measured response to ``quiet`` (the
    quietest level): near 0 for a model that returns to rest, the size of
    its self-sustained oscillation otherwise."""
    force = np.zeros((250_000, 1))
    force[:20] = 1.0
    ringing = model.predict(force)[-50_000:]
    return {"radius": model.model_.normalised.radius_at_rest(),
            "ringing_over_quietest": (np.sqrt(np.mean(ringing**2, axis=0)) /
                                      np.sqrt(np.mean(quiet.y[0] ** 2, axis=0))).tolist()}


def split(predictions, test):
    """{level: (in-band, above-band) NRMSE per output} of the predictions."""
    out = {}
    for lv in TEST_LEVELS:
        bands = nrmse_by_band(test[lv].y, predictions[lv][None], fs=FS, edges=(0.0, CUTOFF, BAND_EDGES[-1]))
        out[lv] = bands[0], bands[1]
    return out


def budget(parts):
    """Means with either part exact and what reaching TARGET would take."""
    inside = np.array([parts[lv][0] for lv in TEST_LEVELS]).ravel()
    above = np.array([parts[lv][1] for lv in TEST_LEVELS]).ravel()

    def mean(i, a):
        return float(np.mean(np.hypot(i, a)))

    row = {"mean_nrmse": mean(inside, above), "mean_in_band_exact": mean(0 * inside, above),
           "mean_above_band_exact": mean(inside, 0 * above),
           "in_band": {str(lv): parts[lv][0].tolist() for lv in TEST_LEVELS},
           "above_band": {str(lv): parts[lv][1].tolist() for lv in TEST_LEVELS}}
    # the in-band error, equal on every level and output, that reaches TARGET
    row["in_band_needed"] = (brentq(lambda e: mean(e, above) - TARGET, 0.0, 1.0)
                             if mean(0 * inside, above) < TARGET else None)
    # the factor on today's error above the band that reaches TARGET
    row["above_band_factor_needed"] = (brentq(lambda s: mean(inside, s * above) - TARGET, 0.0, 1.0)
                                       if mean(inside, 0 * above) < TARGET < row["mean_nrmse"] else None)
    return row


def moved(A, f_old, f_new, zeta_new):
    """``A`` with its complex pole pair at ``f_old`` Hz moved to ``f_new``
    Hz and damping ratio ``zeta_new`` (eigenvectors kept: the mode's shape
    and participation stay)."""
    lam, T = np.linalg.eig(A)
    s = FS * np.log(lam.astype(complex))
    k = np.argmin(np.where(s.imag > 0, np.abs(np.abs(s) / (2 * np.pi) - f_old), np.inf))
    conj = np.argmin(np.abs(lam - np.conj(lam[k])))
    w = 2 * np.pi * f_new
    lam = lam.copy()
    lam[k] = np.exp((-zeta_new * w + 1j * w * np.sqrt(1 - zeta_new**2)) / FS)
    lam[conj] = np.conj(lam[k])
    return np.real(T @ np.diag(lam) @ np.linalg.inv(T))


def law(kind, force, values, at):
    """A mode's frequency or damping at force ``at`` from its values at the
    estimation levels' forces."""
    if kind == "neighbours":
        return float(np.interp(at, force, values))
    return float(np.polyval(np.polyfit(force, values, 1 if kind == "line" else 2), at))


def interpolation_costs(data, models):
    """Per test level and mode: the measured frequency and damping, each
    law's and each model's, and the NRMSE per output that moving the mode
    there costs the level's own linear model."""
    levels = sorted(data)
    measured = modes_by_level([data[lv].X for lv in levels], [data[lv].y for lv in levels], n_states=10,
                              period=PERIOD, fs=FS)
    train = [levels.index(lv) for lv in TRAIN_LEVELS]
    force = measured.input_rms[train]
    per_model = [modes_by_level([data[lv].X for lv in TEST_LEVELS], [data[lv].y for lv in TEST_LEVELS], model,
                                n_states=10, period=PERIOD, fs=FS) for model in models]
    out = {}
    for j, lv in enumerate(TEST_LEVELS):
        i = levels.index(lv)
        own = BLAEstimator(10, period=PERIOD, fs=FS).fit(data[lv].X, data[lv].y)
        reference = own.predict(data[lv].X)[0]
        rms = np.sqrt(np.mean(data[lv].y[0] ** 2, axis=0))
        own_f, _ = modal_parameters(own.A_, FS)
        rows = []
        for k in range(measured.frequencies.shape[1]):
            f, z = measured.frequencies[i, k], measured.damping[i, k]
            if np.isnan(f) or np.any(np.isnan(measured.frequencies[train, k])):
                continue
            f_own = own_f[np.argmin(np.abs(own_f - f))]
            targets = {kind: (law(kind, force, measured.frequencies[train, k], measured.input_rms[i]),
                              law(kind, force, measured.damping[train, k], measured.input_rms[i]))
                       for kind in LAWS}
            for d, modes in enumerate(per_model):
                targets[f"model draw {d}"] = modes.model_frequencies[j, k], modes.model_damping[j, k]
            costs = {}
            for name, (f_new, z_new) in targets.items():
                if np.isnan(f_new):
                    continue
                shifted = copy.copy(own)
                shifted.A_ = moved(own.A_, f_own, f_new, z_new)
                error = np.sqrt(np.mean((shifted.predict(data[lv].X)[0] - reference) ** 2, axis=0)) / rms
                costs[name] = {"frequency_hz": float(f_new), "damping": float(z_new), "nrmse": error.tolist()}
            rows.append({"frequency_hz": float(f), "damping": float(z), "costs": costs})
        out[str(lv)] = rows
    return out


def interpolation_floor(costs, above):
    """Per law (and model): the in-band NRMSE per level and output that its
    modes' misses alone give (their costs added in power), and the mean
    NRMSE over levels and outputs with that in band and ``above`` (a
    draw's error above the band) beside it."""
    names = {name for lv in TEST_LEVELS for mode in costs[str(lv)] for name in mode["costs"]}
    out = {}
    for name in sorted(names):
        inside = {str(lv): np.sqrt(sum(np.square(mode["costs"][name]["nrmse"]) for mode in costs[str(lv)]
                                       if name in mode["costs"])).tolist() for lv in TEST_LEVELS}
        mean = float(np.mean([np.hypot(inside[str(lv)], above[str(lv)]) for lv in TEST_LEVELS]))
        out[name] = {"in_band": inside, "mean_nrmse_with_above_band": mean}
    return out


def print_budget(name, row):
    print(f"{name}: mean {row['mean_nrmse']:.4f}; in band exact {row['mean_in_band_exact']:.4f}, "
          f"above the band exact {row['mean_above_band_exact']:.4f}", flush=True)
    if "at_rest" in row:
        rest = row["at_rest"]
        print(f"   at rest: spectral radius {rest['radius']:.6f}; with no force it rings at "
              + "/".join(f"{v:.3f}" for v in rest["ringing_over_quietest"]) + " of level 1's response", flush=True)
    for lv in TEST_LEVELS:
        print(f"   L{lv} in band " + "/".join(f"{v:.3f}" for v in row["in_band"][str(lv)])
              + "  above " + "/".join(f"{v:.3f}" for v in row["above_band"][str(lv)]), flush=True)
    need_in = row["in_band_needed"]
    need_above = row["above_band_factor_needed"]
    print(f"   {TARGET} needs an in-band error of " + (f"{need_in:.3f} everywhere" if need_in else "(unreachable)")
          + ", or the error above the band times " + (f"{need_above:.2f}" if need_above else "(n/a)"), flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=DEFAULT_DATA)
    parser.add_argument("--draws", type=int, default=3)
    parser.add_argument("--also-stable-at-rest", action="store_true",
                        help="also each draw fitted with stable_at_rest=True")
    parser.add_argument("--output", default=RESULTS / "f16_error_budget.json")
    args = parser.parse_args(argv)

    data = {lv: load_f16(args.data_dir, level=lv, validation_level=None) for lv in range(1, 8)}
    test = {lv: data[lv] for lv in TEST_LEVELS}
    X = np.concatenate([data[lv].X for lv in TRAIN_LEVELS])
    y = np.concatenate([data[lv].y for lv in TRAIN_LEVELS])
    results = header()
    results["target"] = TARGET
    results["model"] = ("AboveBandRegressor(DecoupledPNLSSRegressor(18, 3, 5, signed_powers) random), "
                        "bench_f16.py's --decoupled 3:5:18 --branch-basis signed_powers --above-band")
    t0 = time.perf_counter()
    start = BLAEstimator(18, period=PERIOD, fs=FS).fit(X, y)
    models, predictions = [], []
    for seed in range(args.draws):
        model, wrapped = fit_draw(X, y, start, seed)
        models.append(model)
        predictions.append({lv: wrapped.predict(test[lv].X)[0] for lv in TEST_LEVELS})
        print(f"draw {seed} fitted ({time.perf_counter() - t0:.0f} s in all)", flush=True)
    results["fit_s"] = time.perf_counter() - t0

    results["draws"] = []
    for seed, (model, prediction) in enumerate(zip(models, predictions)):
        row = {**budget(split(prediction, test)), "at_rest": at_rest(model, data[1])}
        print_budget(f"draw {seed}", row)
        results["draws"].append(row)
    if args.also_stable_at_rest:
        results["stable_at_rest"] = []
        for seed in range(args.draws):
            t1 = time.perf_counter()
            model, wrapped = fit_draw(X, y, start, seed, stable_at_rest=True)
            row = {**budget(split({lv: wrapped.predict(test[lv].X)[0] for lv in TEST_LEVELS}, test)),
                   "at_rest": at_rest(model, data[1]), "fit_s": time.perf_counter() - t1}
            print_budget(f"draw {seed}, stable_at_rest=True", row)
            results["stable_at_rest"].append(row)
    if args.draws > 1:
        average = {lv: np.mean([p[lv] for p in predictions], axis=0) for lv in TEST_LEVELS}
        row = budget(split(average, test))
        row["nrmse"] = {str(lv): nrmse_of(average[lv], test[lv].y[0]).tolist() for lv in TEST_LEVELS}
        print_budget(f"the {args.draws} draws averaged", row)
        results["averaged"] = row

    results["interpolation"] = costs = interpolation_costs(data, models)
    for lv in TEST_LEVELS:
        for mode in costs[str(lv)]:
            print(f"L{lv} mode {mode['frequency_hz']:.3f} Hz {100 * mode['damping']:.2f} %: " + "; ".join(
                f"{name} {c['frequency_hz']:.4f} Hz {100 * c['damping']:.2f} % costs "
                + "/".join(f"{v:.3f}" for v in c["nrmse"]) for name, c in mode["costs"].items()), flush=True)
    results["interpolation_floor"] = floor = interpolation_floor(costs, results["draws"][0]["above_band"])
    for name, row in floor.items():
        print(f"the modes' misses alone, {name}: in band " + "  ".join(
            f"L{lv} " + "/".join(f"{v:.3f}" for v in row["in_band"][str(lv)]) for lv in TEST_LEVELS)
            + f"; with draw 0's error above the band, mean {row['mean_nrmse_with_above_band']:.4f}", flush=True)
    write_results(results, args.output)


if __name__ == "__main__":
    main()
