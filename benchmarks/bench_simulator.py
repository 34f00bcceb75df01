"""Benchmark of the Bouc-Wen simulator: speed and fidelity to the official data.

Measures

* the numba compilation of the integrator, reported apart from run times:
  the first call in a fresh interpreter with an empty cache (a cold compile,
  as after a fresh install) and with the on-disk cache already filled (what
  every later session pays);
* the same for a user's own element (a new ``CustomForce`` function in a
  fresh interpreter, the cache filled): the function and its dispatch are
  compiled, the integrator is loaded from the cache;
* ``simulate_bouc_wen`` on one 8192-sample multisine period (periodic steady
  state) and on the 153000-sample benchmark sweep (from rest);
* the default ``make_bouc_wen()`` with ``n_jobs=1`` and ``n_jobs=2``;
* when the official files are present, the relative rms error of the
  re-simulated test outputs against ``yval_multisine`` (periodic, 2-2-5
  decimation) and ``yval_sinesweep`` (from rest, single-stage decimation),
  the latter also with the chirp evaluated exactly at the integration rate
  instead of interpolated from the 750 Hz samples.

Results are printed and written as JSON (default
``benchmarks/results/simulator.json``). Run from anywhere::

    python benchmarks/bench_simulator.py [--data-dir DIR] [--repeat N] [--output FILE]
"""
import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import DEFAULT_DATA, RESULTS, first_call, header, timeit, write_results  # noqa: E402

DEFAULT_OUTPUT = RESULTS / "simulator.json"

# Runs in a fresh interpreter so that nothing is compiled or loaded yet; the
# second call on the same (short) input is the run time to subtract.
_FIRST_CALL = """
import json, time
t0 = time.perf_counter()
import numpy as np
from sklearn_pnlss.datasets import simulate_bouc_wen
t1 = time.perf_counter()
from sklearn_pnlss.signals import multisine
u = multisine(256, rms=50.0, random_state=0)[0][0, :, 0]
simulate_bouc_wen(u, periodic=True)
t2 = time.perf_counter()
simulate_bouc_wen(u, periodic=True)
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first_call": t2 - t1, "second_call": t3 - t2}))
"""

# The same with a user's element: a function new to this interpreter (the
# Bouc-Wen oscillator plus a cubic spring of the user's own).
_FIRST_CUSTOM_CALL = """
import json, time
t0 = time.perf_counter()
import numpy as np
from numba import njit
from sklearn_pnlss.datasets import bouc_wen_oscillator
from sklearn_pnlss.physics import CustomForce
from sklearn_pnlss.signals import multisine
@njit
def users_spring(p, y, yd):
    return p[0] * y**3, 3.0 * p[0] * y**2, 0.0
osc = bouc_wen_oscillator()
osc = osc.with_forces(osc.forces + (CustomForce(users_spring, [1e9]),))
u = multisine(256, rms=50.0, random_state=0)[0][0, :, 0]
t1 = time.perf_counter()
osc.simulate(u, fs=750.0, periodic=True)
t2 = time.perf_counter()
osc.simulate(u, fs=750.0, periodic=True)
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first_call": t2 - t1, "second_call": t3 - t2}))
"""


def _relative_rms(y_true, y_pred):
    y_true, y_pred = np.ravel(y_true), np.ravel(y_pred)
    return float(np.sqrt(np.mean((y_true - y_pred) ** 2) / np.mean(y_true**2)))


def run(data_dir, repeat):
    from sklearn_pnlss.datasets import bouc_wen_oscillator, load_bouc_wen_official, make_bouc_wen, simulate_bouc_wen
    from sklearn_pnlss.signals import bouc_wen_sweep, multisine

    results = header()

    print("numba compilation (first call in a fresh interpreter, 256-sample input)")
    with tempfile.TemporaryDirectory() as empty_cache:
        cold = first_call(_FIRST_CALL, empty_cache)
    with tempfile.TemporaryDirectory() as empty_cache:  # a fresh install's first element of the user's own
        custom_cold = first_call(_FIRST_CUSTOM_CALL, empty_cache)
    warm = first_call(_FIRST_CALL)
    custom = first_call(_FIRST_CUSTOM_CALL)
    results["compile"] = {"cold_cache": cold, "warm_cache": warm, "custom_element_cold_cache": custom_cold,
                          "custom_element_warm_cache": custom}
    print(f"  cold cache: compile {cold['compile_or_load']:.2f} s "
          f"(first call {cold['first_call']:.2f} s, import {cold['import']:.2f} s)")
    print(f"  warm cache: load    {warm['compile_or_load']:.2f} s "
          f"(first call {warm['first_call']:.2f} s, import {warm['import']:.2f} s)")
    print(f"  a user's element, cold cache: compile {custom_cold['compile_or_load']:.2f} s")
    print(f"  a user's element, warm cache: compile its function and load {custom['compile_or_load']:.2f} s "
          f"(first call {custom['first_call']:.2f} s)")

    # Warm up in this process too, so the timings below are run times only.
    # (A 50 N input: at very small amplitudes the hysteresis barely forgets
    # its initial state and the periodic steady state takes many periods.)
    simulate_bouc_wen(multisine(256, rms=50.0, random_state=0)[0][0, :, 0], periodic=True)

    X, _ = multisine(8192, fs=750.0, f_band=(5.0, 150.0), rms=50.0, random_state=0)
    u_period = X[0, :, 0]
    u_sweep = bouc_wen_sweep(153000, 750.0)
    timing = {}
    print(f"run times (median of {repeat})")
    timing["simulate_period_8192"], _ = timeit(
        lambda: simulate_bouc_wen(u_period, periodic=True), repeat)
    print(f"  simulate_bouc_wen, one 8192-sample period (periodic): "
          f"{timing['simulate_period_8192']['median_s']:.3f} s")
    timing["simulate_sweep_153000"], _ = timeit(
        lambda: simulate_bouc_wen(u_sweep, periodic=False, decimation=(20,)), repeat)
    print(f"  simulate_bouc_wen, 153000-sample sweep (from rest):   "
          f"{timing['simulate_sweep_153000']['median_s']:.3f} s")
    for n_jobs in (1, 2):
        key = f"make_bouc_wen_n_jobs_{n_jobs}"
        timing[key], _ = timeit(lambda n_jobs=n_jobs: make_bouc_wen(random_state=0, n_jobs=n_jobs), repeat)
        print(f"  make_bouc_wen() (2 x 2 periods + tests), n_jobs={n_jobs}:    "
              f"{timing[key]['median_s']:.3f} s")
    results["timing"] = timing

    data_dir = Path(data_dir)
    if (data_dir / "uval_multisine.mat").is_file():
        official = load_bouc_wen_official(data_dir)
        y_ms = simulate_bouc_wen(official.X_test_multisine[0, :, 0], periodic=True)
        y_sw = simulate_bouc_wen(official.X_test_sweep[0, :, 0], periodic=False,
                                 decimation=(20,))
        # simulate_bouc_wen interpolates the 750 Hz sweep by FFT; evaluating
        # the chirp formula at 15 kHz (as make_bouc_wen does) is exact.
        y_sw_exact = bouc_wen_oscillator().simulate(
            official.X_test_sweep[0, :, 0], fs=750.0, periodic=False, decimation=(20,),
            u_fine=bouc_wen_sweep(153000, 750.0, oversampling=20))
        fidelity = {
            "data_dir": str(data_dir),
            "multisine_relative_rms": _relative_rms(official.y_test_multisine, y_ms),
            "sweep_relative_rms": _relative_rms(official.y_test_sweep, y_sw),
            "sweep_exact_input_relative_rms": _relative_rms(official.y_test_sweep, y_sw_exact),
        }
        print("fidelity to the official test outputs (relative rms error)")
        print(f"  yval_multisine (periodic, decimation 2-2-5): {fidelity['multisine_relative_rms']:.2e}")
        print(f"  yval_sinesweep (from rest, decimation 20):   {fidelity['sweep_relative_rms']:.2e}")
        print(f"  yval_sinesweep, chirp evaluated at 15 kHz:   "
              f"{fidelity['sweep_exact_input_relative_rms']:.2e}")
    else:
        fidelity = {"data_dir": str(data_dir), "skipped": "official files not found"}
        print(f"fidelity: skipped, official files not found in {data_dir}")
    results["fidelity"] = fidelity
    return results


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=str(DEFAULT_DATA),
                        help="folder with the official Bouc-Wen .mat files "
                             "(default: $SKLEARN_PNLSS_DATA or ../shared/data/bouc_wen)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="timed calls per measurement; the median is reported (default 3)")
    parser.add_argument("--output", default=str(DEFAULT_OUTPUT),
                        help="JSON file to write (default benchmarks/results/simulator.json)")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be >= 1")
    results = run(args.data_dir, args.repeat)
    write_results(results, args.output)


if __name__ == "__main__":
    main()
