"""How far the F-16 model of the band spreads over random starts: the
members of ``f16_lru.py``'s draws, on more seeds than its four draws
(issue 35).

    python benchmarks/f16_member_spread.py [--seeds 16] [--member KEY=VALUE ...] [--data-dir DIR] [--output FILE]

``f16_lru.py`` scores the model of the protocol, the mean of two draws of
two members each with networks above the band, on draws 0-1 and 2-3 only:
four seeds of a random start per pair, too few to say where a pair of
draws usually lands. Its networks (172 to 175 s a draw) make more draws
dear; its members (about 50 s a pair) do not. This script fits
``--seeds`` members exactly as ``f16_lru.py``'s draws do (draw ``k``'s
members seeded ``2k`` and ``2k + 1``, two side by side,
``DecoupledPNLSSRegressor(18, 3, 5, signed_powers)`` from one random
start each, the estimation levels' sweeps as check records), and scores
on the test multisines (periodic steady state): each member (with the
iterate its fit kept and why), each consecutive pair of draws' model of
the band (four members, as ``f16_lru.py``'s pairs have), and every set of
four members of all those fitted: the spread of the model of the band
that the networks above it leave as it is. Writes
``results/f16_member_spread.json``. ``--member`` changes a member setting
to measure a variant on the same seeds (``--member degree=3 --member
n_init=2 --output /tmp/variant.json``).
"""
import argparse
import ast
import itertools
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_f16  # noqa: E402
import f16_lru  # noqa: E402
from _bench_utils import RESULTS, header, write_results  # noqa: E402
from f16_clearances import BASIS, BRANCHES, DEGREE, STATES, load_and_start  # noqa: E402

# members of a model of the band in f16_lru.py's pair of draws
PAIR_MEMBERS = 4


def fit_draw(draw, Xs, y, check_records, member_settings):
    """Draw ``draw``'s two members, fitted side by side as f16_lru.py's
    draws fit them but for ``member_settings``, with the fits' warnings
    about the kept iterate."""
    averaged = f16_lru.averaged(draw)[2].set_params(**{f"regressor__{k}": v for k, v in member_settings.items()})
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        averaged.fit(Xs, y, X_check=check_records)
    fit_s = time.perf_counter() - t0
    kept = [str(w.message) for w in caught if "is kept instead" in str(w.message)]
    return averaged.estimators_, fit_s, kept


def _value(text):
    """A ``--member`` value: a Python literal (3, 0.5, True), else the text."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def score(predictions, test, seeds):
    """Per level and output, and the mean, of the mean of ``seeds``'
    predictions of the test multisines."""
    per_level = {str(lv): bench_f16.nrmse_of(np.mean([predictions[s][lv] for s in seeds], axis=0), d.y[0]).tolist()
                 for lv, d in test.items()}
    return per_level, float(np.mean([v for row in per_level.values() for v in row]))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=bench_f16.DEFAULT_DATA)
    parser.add_argument("--seeds", type=int, default=16, help="members fitted (an even number: two per draw)")
    parser.add_argument("--member", action="append", default=[], metavar="KEY=VALUE",
                        help="a member setting other than f16_lru.py's (degree=3, n_init=2, stable_at_rest=True)")
    parser.add_argument("--output", default=RESULTS / "f16_member_spread.json")
    args = parser.parse_args(argv)
    if args.seeds < PAIR_MEMBERS or args.seeds % 2:
        parser.error(f"--seeds must be even and at least {PAIR_MEMBERS}")
    if any("=" not in kv for kv in args.member):
        parser.error("--member takes KEY=VALUE")
    member_settings = {k: _value(v) for k, v in (kv.split("=", 1) for kv in args.member)}

    X, y, test, train_sweeps, start, start_s = load_and_start(args.data_dir)
    Xs, check_records = start.transform(X), [d.X[0] for d in train_sweeps]
    results = {**header(), "protocol": {"train_levels": bench_f16.TRAIN_LEVELS, "test_levels": bench_f16.TEST_LEVELS},
               "model": {"n_states": STATES, "n_branches": BRANCHES, "degree": DEGREE, "branch_basis": BASIS,
                         "n_init": 1, "check_records": "the estimation levels' sine sweeps", **member_settings},
               "start_s": start_s, "draws": [], "members": []}
    predictions = {}
    for draw in range(args.seeds // 2):
        members, fit_s, kept = fit_draw(draw, Xs, y, check_records, member_settings)
        for member in members:
            seed = int(member.random_state)
            predictions[seed] = {lv: member.predict(d.X)[0] for lv, d in test.items()}
            per_level, mean = score(predictions, test, [seed])
            results["members"].append({
                "seed": seed, "mean_nrmse": mean, "nrmse": per_level, "n_iter": int(member.n_iter_),
                "kept_iteration": int(member.best_iteration_), "radius_at_rest": bench_f16.radius_at_rest(member)})
            print(f"seed {seed:2d}: mean {mean:.4f}  L2 {np.mean(per_level['2']):.3f}  iterate "
                  f"{member.best_iteration_} of {member.n_iter_}", flush=True)
        results["draws"].append({"draw": draw, "seeds": [int(m.random_state) for m in members], "fit_s": fit_s,
                                 "kept_earlier": kept})
        write_results(results, args.output)

    seeds = sorted(predictions)
    pairs = [seeds[i:i + PAIR_MEMBERS] for i in range(0, len(seeds) - PAIR_MEMBERS + 1, PAIR_MEMBERS)]
    every = np.array([score(predictions, test, list(c))[1] for c in itertools.combinations(seeds, PAIR_MEMBERS)])
    results["pairs_of_draws"] = []
    for chosen in pairs:
        per_level, mean = score(predictions, test, chosen)
        results["pairs_of_draws"].append({"seeds": chosen, "mean_nrmse": mean, "nrmse": per_level,
                                          "fraction_of_sets_below": float(np.mean(every < mean))})
        print(f"pair of draws, members {chosen}: mean {mean:.4f} (below it: {np.mean(every < mean):.0%} of the sets "
              f"of {PAIR_MEMBERS})", flush=True)
    quantiles = dict(zip(("min", "p10", "median", "p90", "max"), np.quantile(every, [0, 0.1, 0.5, 0.9, 1.0])))
    results["every_set_of_four"] = {"n_sets": int(every.size), **{k: float(v) for k, v in quantiles.items()}}
    print(f"every set of {PAIR_MEMBERS} of the {len(seeds)} members ({every.size}): "
          + ", ".join(f"{k} {v:.4f}" for k, v in quantiles.items()), flush=True)
    write_results(results, args.output)


if __name__ == "__main__":
    main()
