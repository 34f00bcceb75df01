"""Gap diagnosis on cases drawn at random, none of them a case its rules
were set on: does it carry over?

``gap_withheld.py`` holds the families the diagnosis was built and checked
on: one structure (2 kg, 25 Hz, 2 % damping), one input level, two
strengths per effect.  Here every seed draws a case of its own:

- the structure: mass 0.5-5 kg, natural frequency 8-40 Hz, damping ratio
  1-5 %;
- the training data: 2-5 multisine realisations of 2-4 periods of 4096 or
  8192 samples at 750 Hz, excited from 2 Hz to four times the natural
  frequency (at most 150 Hz), 10-100 N rms; band-limited output noise 40 to
  60 dB below the response;
- the validation data: one more multisine period and a sweep through the
  same band;
- the truth: no effect, one built-in effect with its shape drawn (a
  backlash's gap, a hysteresis' loop, a second mode's frequency and
  damping), or one that is no candidate: an odd quadratic spring
  ``k y |y|`` (a user's element; the built-in quadratic spring is even) or
  a built-in effect removed from the candidates.  A force element's
  strength is set so that the error it alone makes in the nominal's
  response to the training input is 10 to 25 dB below that response.

The right answer is the effect's name, no effect for the null case, and
"unexplained" for an effect that is no candidate.  Writes
``results/gap_generated.json``; ``--update`` adds seeds to it.

    python benchmarks/gap_generated.py --seeds 24
    python benchmarks/gap_generated.py --first-seed 24 --seeds 8 --update
"""
import argparse
import json
import sys
import time
from collections import Counter

import numpy as np
from _bench_utils import RESULTS, commit_of, header
from numba import njit

from sklearn_pnlss.gap import GapDiagnosis, default_effects
from sklearn_pnlss.gap.candidates.effects import delay_signal
from sklearn_pnlss.gap.fitting.simulate import SignalSet, simulate_signals
from sklearn_pnlss.physics import (
    BoucWen,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    CustomForce,
    DeadZoneSpring,
    Oscillator,
    QuadraticDamping,
    QuadraticStiffness,
    StiffnessDrift,
)
from sklearn_pnlss.signals import linear_chirp, multisine

FS, OVERSAMPLING = 750.0, 20
OUT = RESULTS / "gap_generated.json"
COMMIT = commit_of()

#: The truths a seed draws from (the null case and the effects no candidate
#: holds as often as each effect).
TRUTHS = ["null", "cubic_stiffness", "quadratic_stiffness", "coulomb_friction", "quadratic_damping", "backlash",
          "hysteresis", "input_saturation", "input_delay", "second_mode", "stiffness_drift", "recalibration",
          "odd_quadratic_spring", "removed"]


@njit
def _odd_quadratic(p, y, yd):
    return p[0] * y * abs(y), 2.0 * p[0] * abs(y), 0.0


def _structure(rng):
    m = rng.uniform(0.5, 5.0)
    f0 = rng.uniform(8.0, 40.0)
    zeta = rng.uniform(0.01, 0.05)
    k = m * (2 * np.pi * f0) ** 2
    return Oscillator(m, 2 * zeta * np.sqrt(k * m), k), f0


def _inputs(rng, f0):
    period = int(rng.choice([4096, 8192]))
    f_band = (2.0, min(4 * f0, 150.0))
    rms = rng.uniform(10.0, 100.0)
    n_real, n_per = int(rng.integers(2, 6)), int(rng.integers(2, 5))
    seed = int(rng.integers(1 << 30))
    X, _ = multisine(period, fs=FS, f_band=f_band, rms=rms, n_periods=n_per, n_realizations=n_real,
                     random_state=seed)
    V, _ = multisine(period, fs=FS, f_band=f_band, rms=rms, n_periods=1, n_realizations=1, random_state=seed + 1)
    duration = (3 * period - 100) / FS  # no whole number of periods: not taken for steady state
    t = np.arange(3 * period - 100) / FS
    sweep = linear_chirp(t, f_start=f_band[0], rate=(f_band[1] - f_band[0]) / duration, amplitude=rms * np.sqrt(2))
    return [x[:, 0] for x in X], [V[0, :, 0], sweep], period, dict(period=period, f_band=f_band, rms=rms,
                                                                   realisations=n_real, periods=n_per)


def _error_rms(osc, transform, train, y_nominal):
    """Rms error ``osc`` makes in the nominal's response (inf where it
    diverges: a strong even spring lets the mass escape)."""
    try:
        y = simulate_signals(osc, train, transform, record=True)
    except FloatingPointError:
        return np.inf
    return float(np.sqrt(np.mean(np.concatenate([a - b for a, b in zip(y, y_nominal)]) ** 2)))


def _scaled(make, p0, nominal, train, y_nominal, target):
    """The element ``make(p)`` whose error alone is ``target`` (rms):
    secant steps on its strength from the weak ``p0``, halved while the
    response diverges."""
    p = p0
    for _ in range(4):
        error = _error_rms(nominal.with_forces((make(p),)), None, train, y_nominal)
        while not np.isfinite(error):
            p /= 2
            error = _error_rms(nominal.with_forces((make(p),)), None, train, y_nominal)
        p *= target / max(error, 1e-300)
    while not np.isfinite(_error_rms(nominal.with_forces((make(p),)), None, train, y_nominal)):
        p /= 2
    return make(p)


def draw_case(seed):
    """Everything of one case: the nominal, the true system's elements,
    linear changes and input transform, the data and the right answer."""
    rng = np.random.default_rng(seed)
    nominal, f0 = _structure(rng)
    u_train, u_val, period, data = _inputs(rng, f0)
    truth = TRUTHS[seed % len(TRUTHS)]
    train = SignalSet.from_signals(u_train, period, FS, OVERSAMPLING)
    y_nominal = simulate_signals(nominal, train)
    y_rms = float(np.sqrt(np.mean(np.concatenate(y_nominal) ** 2)))
    v_rms = y_rms * 2 * np.pi * f0
    target = y_rms * 10 ** (-rng.uniform(10.0, 25.0) / 20)
    k, c = nominal.stiffness, nominal.damping
    forces, linear, transform, candidates = (), {}, None, None
    name = truth
    if truth == "removed":
        name = str(rng.choice(["hysteresis", "backlash", "second_mode", "cubic_stiffness"]))
        candidates = [e for e in default_effects() if e != name]
    if name == "cubic_stiffness":
        forces = (_scaled(CubicStiffness, 0.01 * k / y_rms**2, nominal, train, y_nominal, target),)
    elif name == "quadratic_stiffness":
        forces = (_scaled(QuadraticStiffness, 0.01 * k / y_rms, nominal, train, y_nominal, target),)
    elif name == "odd_quadratic_spring":
        forces = (_scaled(lambda p: CustomForce(_odd_quadratic, [p]), 0.01 * k / y_rms, nominal, train, y_nominal,
                          target),)
    elif name == "coulomb_friction":
        smooth = rng.uniform(0.005, 0.03) * v_rms
        forces = (_scaled(lambda p: CoulombFriction(p, smooth), 0.01 * c * v_rms, nominal, train, y_nominal, target),)
    elif name == "quadratic_damping":
        forces = (_scaled(QuadraticDamping, 0.01 * c / v_rms, nominal, train, y_nominal, target),)
    elif name == "backlash":
        gap = rng.uniform(0.3, 1.2) * y_rms
        forces = (_scaled(lambda p: DeadZoneSpring(p, gap), 0.01 * k, nominal, train, y_nominal, target),)
    elif name == "hysteresis":
        beta, delta = rng.uniform(0.3, 1.0) / y_rms, rng.uniform(-1.1, -0.4)
        forces = (_scaled(lambda p: BoucWen(p, beta, 0.8, delta, 1.0), 0.01 * k, nominal, train, y_nominal, target),)
    elif name == "second_mode":
        ratio, m2 = rng.uniform(0.5, 3.0), rng.uniform(0.1, 0.3) * nominal.mass
        k2, zeta2 = m2 * (2 * np.pi * ratio * f0) ** 2, rng.uniform(0.01, 0.05)
        forces = (CoupledMass(m2, 2 * zeta2 * np.sqrt(k2 * m2), k2),)
    elif name == "stiffness_drift":
        duration = max(u.size for u in u_train) / FS
        forces = (StiffnessDrift(-rng.uniform(0.02, 0.05) * k / duration),)
    elif name == "recalibration":
        linear = dict(stiffness=k * (1 + rng.choice([-1, 1]) * rng.uniform(0.03, 0.1)),
                      damping=c * (1 + rng.choice([-1, 1]) * rng.uniform(0.0, 0.4)))
    elif name == "input_saturation":
        level = rng.uniform(0.6, 0.85) * max(np.max(np.abs(u)) for u in u_train)
        transform = lambda u, fs, periodic: np.clip(u, -level, level)  # noqa: E731
    elif name == "input_delay":
        seconds = rng.uniform(0.5, 3.0) * 1e-3
        transform = lambda u, fs, periodic: delay_signal(u, seconds * fs, periodic)  # noqa: E731
    expected = ("unexplained" if truth in ("removed", "odd_quadratic_spring") else
                None if truth == "null" else name)
    real = nominal.with_forces(forces, **linear)
    noise = y_rms * 10 ** (-rng.uniform(40.0, 60.0) / 20)
    data.update(truth=truth, effect=name, forces=[repr(f) for f in forces], linear=linear, noise_rms=noise,
                nominal=[nominal.mass, nominal.damping, nominal.stiffness], f0=f0)
    val = SignalSet.from_signals(u_val, period, FS, OVERSAMPLING)
    noise_rng = np.random.RandomState(seed)
    y_train = simulate_signals(real, train, transform, noise_rms=noise, random_state=noise_rng, record=True)
    y_val = simulate_signals(real, val, transform, noise_rms=noise, random_state=noise_rng, record=True)
    return nominal, candidates, (u_train, y_train, u_val, y_val, period), expected, data


def run_case(seed, n_jobs):
    nominal, candidates, (u_train, y_train, u_val, y_val, period), expected, data = draw_case(seed)
    t0 = time.perf_counter()
    diag = GapDiagnosis(nominal, fs=FS, period=period, effects=candidates, n_jobs=n_jobs,
                        random_state=seed).fit(u_train, y_train)
    report = diag.report(u_val, y_val)
    seconds = time.perf_counter() - t0
    return dict(seed=seed, commit=COMMIT, expected=expected, got=report.best_effect,
                ok=report.best_effect == expected, seconds=seconds, gap_db=report.gap_db,
                noise_floor_db=report.noise_floor_db, case=data,
                ranking=[(r.name, round(r.gap_after_db, 2), round(r.closure, 3)) for r in report.ranking[:4]],
                reason=report.reason)


def _summary(rows):
    effects = [r for r in rows if r["expected"] not in (None, "unexplained")]
    return dict(cases=len(rows), right=sum(r["ok"] for r in rows),
                effect_accuracy=float(np.mean([r["ok"] for r in effects])) if effects else None,
                null_false_alarms=sum(1 for r in rows if r["expected"] is None and not r["ok"]),
                unexplained_ok=[r["ok"] for r in rows if r["expected"] == "unexplained"],
                median_seconds=float(np.median([r["seconds"] for r in rows])),
                max_seconds=max(r["seconds"] for r in rows),
                wrong={f"{r['case']['truth']} (seed {r['seed']})": r["got"] for r in rows if not r["ok"]})


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=len(TRUTHS))
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--n-jobs", type=int, default=2)
    parser.add_argument("--update", action="store_true", help="add these seeds to the results file")
    args = parser.parse_args(argv)
    kept = json.loads(OUT.read_text())["rows"] if args.update and OUT.exists() else []
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    kept = [r for r in kept if r["seed"] not in seeds]
    rows = []
    for seed in seeds:
        row = run_case(seed, args.n_jobs)
        rows.append(row)
        c = row["case"]
        print(f"seed {seed:<3} {c['truth']:<21} {c['nominal'][0]:.2f} kg {c['f0']:5.1f} Hz  expected "
              f"{str(row['expected']):<20} got {str(row['got']):<20} {'ok ' if row['ok'] else 'BAD'} "
              f"{row['seconds']:6.1f} s  gap {row['gap_db']:.1f} dB", flush=True)
        if not row["ok"]:
            print(f"    {row['reason']}\n    {row['ranking']}", flush=True)
        everything = sorted(kept + rows, key=lambda r: r["seed"])
        RESULTS.mkdir(exist_ok=True)
        OUT.write_text(json.dumps(dict(header(), summary=_summary(everything), rows=everything), indent=1,
                                  default=str))
    print(json.dumps(_summary(sorted(kept + rows, key=lambda r: r["seed"])), indent=1))
    print(f"written {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
