"""What one integrator step costs, by force element.

The gap diagnosis is mostly Newmark-Newton steps of the oscillator (see
``bench_gap_time.py``).  This times the plain integration (no
sensitivities) of one 8192-sample multisine period at 5 times the data rate
(the diagnosis' fitting rate) from rest, for the nominal of
``gap_withheld.py`` alone and with each force element of its cases, and
prints nanoseconds per step (the median of 7 runs) and Newton iterations
per step.  One thread: the cost of the arithmetic, not of the cores'
sharing.

The structural diagnosis steps :class:`~sklearn_pnlss.physics.Structure`
instead: the 5-point chain of ``gap_structures.py`` (seed 1), linear and
with each law of its family at its joint, one period of its top training
level at 5 times the data rate.  Beside the time, the linear step's
arithmetic: ``2 n (3 n + 1)`` flops for its product and ``8 n`` for the
update, the floor a step cannot go below.

    python benchmarks/bench_integrator_step.py --label after
    git worktree add /tmp/before <commit>
    PYTHONPATH=/tmp/before python benchmarks/bench_integrator_step.py --label before

Each label's rows go to ``results/integrator_step.json`` (other labels
kept), with the commit measured.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from _bench_utils import RESULTS, commit_of, header

import gap_structures as gs
import gap_withheld as gw
import sklearn_pnlss
from sklearn_pnlss.physics import Connection, oscillator
from sklearn_pnlss.physics.prewarp import prewarped
from sklearn_pnlss.physics.resampling import upsample_fft
from sklearn_pnlss.signals import multisine

RATE = 5  # the diagnosis' fitting rate, times the data rate
ELEMENTS = {"linear": None, **{name: cases[0][0][0] for name, cases in gw.CASES.items()
                               if name is not None and cases[0][0]}}


def step_cost(element, u_fine, h, repeats=7):
    """Median seconds per step and Newton iterations per step of a plain
    run from rest."""
    osc = gw.NOMINAL.with_forces(() if element is None else (element,))
    kinds, p_off, params, z_off, _ = osc._packed
    n, nz = u_fine.size, osc.n_internal_states
    times, iterations = [], 0
    for _ in range(repeats + 1):  # the first run compiles or loads the kernel
        state = np.zeros(oscillator.STATE_Z + 2 * nz)
        y, yd, z = np.empty(n), np.empty(n), np.empty((n, nz))
        start = time.perf_counter()
        _, iterations = osc._newmark_run(u_fine, n - 1, h, osc.mass, osc.damping, osc.stiffness, kinds, p_off,
                                         params, z_off, state, True, y, yd, z, oscillator._NEWTON_RTOL,
                                         oscillator._NEWTON_MAX_ITER, oscillator._NO_TANGENTS,
                                         oscillator._NO_PARAMS, oscillator._NO_TANGENTS)
        times.append(time.perf_counter() - start)
    return float(np.median(times[1:])) / (n - 1), iterations / (n - 1)


def structure_step_cost(structure, u_fine, fs, drive, repeats=7):
    """Median seconds per step of a plain run of a structure from rest."""
    times = []
    for _ in range(repeats + 1):  # the first run compiles or loads the kernel
        start = time.perf_counter()
        structure.simulate_fine(u_fine, fs=fs, inputs=[drive])
        times.append(time.perf_counter() - start)
    return float(np.median(times[1:])) / (u_fine.shape[0] - 1)


def structure_rows():
    """ns per step of family s's 5-point chain, linear and with each law."""
    case = gs.make_case("cubic_stiffness", "exact", 1)
    chain, joint, drive = case["nominal"], case["joint"], case["drive"]
    u_fine = upsample_fft(case["X"][-1][:gs.PERIOD, 0], RATE, periodic=True)
    fs = RATE * gs.FS
    rng = np.random.default_rng(0)
    # each law at its family's strength: a share of the joint spring's force
    # at the joint's rms relative motion, linear
    linear = prewarped(chain, fs)
    points = [p for p in joint if p is not None]
    motion = [linear.measure(linear.simulate_fine(u_fine, fs=fs, inputs=[drive]), [(p, kind) for p in points])
              for kind in ("displacement", "velocity")]
    relative = [m[:, 0] - (m[:, 1] if m.shape[1] > 1 else 0.0) for m in motion]
    k_joint = chain.stiffness[chain.points.index(joint[0]), chain.points.index(joint[0])] / 2
    scales = (k_joint, relative[0].std(), relative[1].std())
    n = chain.n_dof
    flops = 2 * n * (3 * n + 1) + 8 * n
    rows = {}
    for law in ("linear",) + tuple(e for e in gs.EFFECTS if e is not None):
        structure = chain if law == "linear" else chain.with_connections(
            [Connection(gs.element(law, scales, rng), *joint)])
        seconds = structure_step_cost(prewarped(structure, fs), u_fine, fs, drive)
        rows[law] = dict(n_dof=n, ns_per_step=round(1e9 * seconds, 1), linear_step_flops=flops)
        print(f"structure, {law:<17} {1e9 * seconds:7.1f} ns per step ({n} points; the linear step's arithmetic "
              f"{flops} flops)", flush=True)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--label", required=True, help="name of this measurement (e.g. before, after)")
    args = parser.parse_args(argv)
    code = Path(sklearn_pnlss.__file__).resolve().parents[1]
    commit = commit_of(code)
    X, _ = multisine(gw.PERIOD, fs=gw.FS, f_band=(5.0, 150.0), rms=50.0, n_periods=1, n_realizations=1,
                     random_state=0)
    u_fine = upsample_fft(X[0, :, 0], RATE, periodic=True)
    h = 1.0 / (RATE * gw.FS)
    rows = {}
    for name, element in ELEMENTS.items():
        seconds, iterations = step_cost(element, u_fine, h)
        rows[name] = dict(ns_per_step=round(1e9 * seconds, 1), newton_iterations_per_step=round(iterations, 3))
        print(f"{name:<22} {1e9 * seconds:7.1f} ns per step, {iterations:.2f} Newton iterations", flush=True)
    structure = structure_rows()
    path = RESULTS / "integrator_step.json"
    out = json.loads(path.read_text()) if path.exists() else {}
    out[args.label] = dict(header(), commit=commit, rate=RATE, steps=u_fine.size - 1, rows=rows,
                           structure_rows=structure)
    path.write_text(json.dumps(out, indent=1))
    print(f"written {path} ({args.label})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
