"""How far the F-16 model of the band spreads over random starts: the
members of ``f16_lru.py``'s draws, on more seeds than its four draws
(issue 35).

    python benchmarks/f16_member_spread.py [--seeds 16] [--member KEY=VALUE ...] [--no-check-outputs]
        [--data-dir DIR] [--output FILE]

``f16_lru.py`` scores the model of the protocol, the mean of two draws of
two members each with networks above the band, on draws 0-1 and 2-3 only:
four seeds of a random start per pair, too few to say where a pair of
draws usually lands. Its networks (175 to 200 s a draw) make more draws
dear; its members (about 90 s a pair) do not. This script fits
``--seeds`` members exactly as ``f16_lru.py``'s draws do (draw ``k``'s
members seeded ``2k`` and ``2k + 1``, two side by side,
``DecoupledPNLSSRegressor(18, 3, 3, signed_powers)``, each the better of
two random starts, the estimation levels' sweeps as check records with
their outputs), and scores each member (with the iterate its fit kept and
why), each consecutive pair of draws' model of the band (four members, as
``f16_lru.py``'s pairs have), and every set of four members of all those
fitted: the spread of the model of the band that the networks above it
leave as it is. Each is scored twice: on the test multisines (periodic
steady state), and, so that no choice of member settings need rest on
the test levels alone, on the estimation levels' sweeps simulated from
rest, inside the excited band (which the fits use only to refuse an
iterate that runs away on one or simulates one worse than its start, never
to choose; each member's excursion past its trusted range on them is
recorded too). ``--no-check-outputs`` leaves their outputs out, as the
runs before the refusal had them. Writes ``results/f16_member_spread.json``.
``--member`` changes a member setting to measure a variant on the same seeds
(``--member degree=5 --member n_init=1 --output /tmp/variant.json``: the
members of the earlier runs, ``bench_f16.py``'s model from one start).
"""
import argparse
import itertools
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
import f16_lru  # noqa: E402
from _bench_utils import RESULTS, header, setting_value, write_results  # noqa: E402
from f16_clearances import load_and_start  # noqa: E402

# members of a model of the band in f16_lru.py's pair of draws
PAIR_MEMBERS = 4


def fit_draw(draw, Xs, y, check_records, check_outputs, member_settings):
    """Draw ``draw``'s two members, fitted side by side as f16_lru.py's
    draws fit them but for ``member_settings``, with the fits' warnings
    about the kept iterate."""
    averaged = f16_lru.averaged(draw, member_settings)[2]
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        averaged.fit(Xs, y, X_check=check_records, y_check=check_outputs)
    fit_s = time.perf_counter() - t0
    kept = [str(w.message) for w in caught if "is kept instead" in str(w.message)]
    return averaged.estimators_, fit_s, kept


def score(predictions, test, seeds):
    """Per level and output, and the mean, of the mean of ``seeds``'
    predictions of the test multisines."""
    per_level = {str(lv): bench_f16.nrmse_of(np.mean([predictions[s][lv] for s in seeds], axis=0), d.y[0]).tolist()
                 for lv, d in test.items()}
    return per_level, float(np.mean([v for row in per_level.values() for v in row]))


def in_band_error(prediction, y):
    """The error of ``prediction`` (samples, outputs) inside the excited
    band, below ``bench_f16.BAND_EDGES[1]`` (a model of the band is not
    asked for more), in time."""
    spectrum = np.fft.rfft(prediction - y, axis=0)
    spectrum[np.fft.rfftfreq(len(y), d=1 / 400.0) >= bench_f16.BAND_EDGES[1]] = 0
    return np.fft.irfft(spectrum, n=len(y), axis=0)


def score_in_band(grams, seeds):
    """The mean over levels and outputs of the in-band NRMSE of the mean
    of ``seeds``' simulations: the squared norm of a mean of errors is the
    mean of their inner products, so ``grams`` (per level, the members'
    in-band errors' inner products over the output's power, (members,
    members, outputs)) scores every set without simulating it again."""
    return float(np.mean([np.sqrt(gram[np.ix_(seeds, seeds)].sum(axis=(0, 1))) / len(seeds) for gram in grams]))


def quantiles(values):
    """min, p10, median, p90 and max of ``values``."""
    return {k: float(v) for k, v in zip(("min", "p10", "median", "p90", "max"),
                                        np.quantile(values, [0, 0.1, 0.5, 0.9, 1.0]))}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--seeds", type=int, default=16, help="members fitted (an even number: two per draw)")
    parser.add_argument("--member", action="append", default=[], metavar="KEY=VALUE",
                        help="a member setting other than f16_lru.py's (degree=5, n_init=1, stable_at_rest=True)")
    parser.add_argument("--check-outputs", action=argparse.BooleanOptionalAction, default=True,
                        help="give the fits the estimation sweeps' outputs (y_check), as f16_lru.py does")
    parser.add_argument("--output", default=RESULTS / "f16_member_spread.json")
    args = parser.parse_args(argv)
    if args.seeds < PAIR_MEMBERS or args.seeds % 2:
        parser.error(f"--seeds must be even and at least {PAIR_MEMBERS}")
    if any("=" not in kv for kv in args.member):
        parser.error("--member takes KEY=VALUE")
    member_settings = {k: setting_value(v) for k, v in (kv.split("=", 1) for kv in args.member)}

    X, y, test, train_sweeps, start, start_s = load_and_start(args.data_dir)
    Xs, check_records = start.transform(X), [d.X[0] for d in train_sweeps]
    check_outputs = [d.y[0] for d in train_sweeps] if args.check_outputs else None
    # the estimation levels' sweeps, scored so that no choice of member settings need rest on the test levels alone
    sweeps = dict(zip(bench_f16.TRAIN_LEVELS, train_sweeps))
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "model": {**f16_lru.decoupled(f16_lru.MEMBER_DEGREE)[1], "n_init": f16_lru.MEMBER_STARTS,
                         "check_records": "the estimation levels' sine sweeps",
                         "check_outputs": args.check_outputs, **member_settings},
               "start_s": start_s, "draws": [], "members": []}
    predictions, sweep_errors = {}, {}
    for draw in range(args.seeds // 2):
        members, fit_s, kept = fit_draw(draw, Xs, y, check_records, check_outputs, member_settings)
        for member in members:
            seed = int(member.random_state)
            predictions[seed] = {lv: member.predict(d.X)[0] for lv, d in test.items()}
            sweep_errors[seed] = {lv: in_band_error(bench_f16.prediction_from_rest(member, d.X[0]), d.y[0])
                                  for lv, d in sweeps.items()}
            on_sweeps = {str(lv): (np.sqrt(np.sum(sweep_errors[seed][lv] ** 2, axis=0) / np.sum(d.y[0] ** 2, axis=0))
                                   .tolist()) for lv, d in sweeps.items()}
            sweeps_mean = float(np.mean(list(on_sweeps.values())))
            per_level, mean = score(predictions, test, [seed])
            results["members"].append({
                "seed": seed, "mean_nrmse": mean, "nrmse": per_level, "estimation_sweeps_in_band": on_sweeps,
                "estimation_sweeps_in_band_mean": sweeps_mean, "n_iter": int(member.n_iter_),
                # how far past its trusted range each sweep takes the member (a runaway from 1 on)
                "estimation_sweeps_excursion": dict(zip(map(str, sweeps), member.range_excursion(
                    [d.X[0] for d in sweeps.values()]).tolist())),
                "kept_iteration": int(member.best_iteration_), "radius_at_rest": bench_f16.radius_at_rest(member)})
            print(f"seed {seed:2d}: mean {mean:.4f}  L2 {np.mean(per_level['2']):.3f}  sweeps {sweeps_mean:.4f}  "
                  f"iterate {member.best_iteration_} of {member.n_iter_}", flush=True)
        results["draws"].append({"draw": draw, "seeds": [int(m.random_state) for m in members], "fit_s": fit_s,
                                 "kept_earlier": kept})
        write_results(results, args.output)

    seeds = sorted(predictions)  # 0 to --seeds - 1: a member's seed is its row in the grams
    errors = {lv: np.array([sweep_errors[s][lv] for s in seeds]) for lv in sweeps}
    grams = [np.einsum("snk,tnk->stk", errors[lv], errors[lv]) / np.sum(d.y[0] ** 2, axis=0)
             for lv, d in sweeps.items()]
    pairs = [seeds[i:i + PAIR_MEMBERS] for i in range(0, len(seeds) - PAIR_MEMBERS + 1, PAIR_MEMBERS)]
    sets = [list(c) for c in itertools.combinations(seeds, PAIR_MEMBERS)]
    every = np.array([score(predictions, test, c)[1] for c in sets])
    results["pairs_of_draws"] = []
    for chosen in pairs:
        per_level, mean = score(predictions, test, chosen)
        results["pairs_of_draws"].append({"seeds": chosen, "mean_nrmse": mean, "nrmse": per_level,
                                          "fraction_of_sets_below": float(np.mean(every < mean)),
                                          "estimation_sweeps_in_band_mean": score_in_band(grams, chosen)})
        print(f"pair of draws, members {chosen}: mean {mean:.4f} (below it: {np.mean(every < mean):.0%} of the sets "
              f"of {PAIR_MEMBERS})", flush=True)
    results["every_set_of_four"] = {"n_sets": int(every.size), **quantiles(every)}
    on_sweeps = quantiles([score_in_band(grams, c) for c in sets])
    results["every_set_of_four_on_estimation_sweeps"] = on_sweeps
    for name, spread in (("test multisines", results["every_set_of_four"]), ("estimation sweeps, in band", on_sweeps)):
        print(f"every set of {PAIR_MEMBERS} of the {len(seeds)} members ({every.size}), {name}: "
              + ", ".join(f"{k} {spread[k]:.4f}" for k in ("min", "p10", "median", "p90", "max")), flush=True)
    write_results(results, args.output)


if __name__ == "__main__":
    main()
