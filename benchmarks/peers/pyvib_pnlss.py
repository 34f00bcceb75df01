"""Time the peer library pyvib on the Bouc-Wen PNLSS benchmark.

pyvib (https://github.com/pawsen/pyvib) is a Python port of the MATLAB PNLSS
toolbox. This script only *runs* it, from a checkout whose path the user
gives with ``--pyvib-path``; no pyvib code is copied into, installed with or
shipped by sklearn_pnlss. Check the licence of the checkout you use (the
COPYING file of commit 3fd96436ef9f is a BSD-2-Clause text). Run the script
with the interpreter of a separate virtual environment that holds pyvib's
dependencies, never with the sklearn_pnlss development environment::

    python3 -m venv /tmp/pyvib-venv
    /tmp/pyvib-venv/bin/pip install numpy scipy matplotlib
    git clone https://github.com/pawsen/pyvib /tmp/pyvib
    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \\
        /tmp/pyvib-venv/bin/python benchmarks/peers/pyvib_pnlss.py \\
        --pyvib-path /tmp/pyvib --max-iter 10

The caller chooses the BLAS/OpenMP thread counts through the environment
(``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS``); the
script reports them, it does not set them.

Workflow, as in pyvib's Bouc-Wen example (``examples/pnlss/boucwen.py``):

1. Data: periods 2-5 of ``train_multisine_official.mat`` (one realisation,
   4 periods of 8192 samples; period 1 is dropped as transient), arranged as
   pyvib's ``(npp, m, R, P)`` array. The excited lines are read off the input
   spectrum (bins 54-1639 for the official record).
2. Linear start: nonparametric BLA (``Signal.bla``), then the
   frequency-domain subspace model with ``n=3, r=4`` (``Subspace.estimate``),
   unweighted and not optimised: the example's final linear model is this
   plain subspace estimate (its ``Subspace.scan`` over n and r is only used
   for plots and is overwritten; with a single realisation the total BLA
   covariance it would weight with is not available anyway). With
   ``--linear-lm-iter K > 0`` the linear model is refined by K iterations of
   pyvib's frequency-domain Levenberg-Marquardt, weighted by the BLA noise
   covariance, and that time is reported apart.
3. PNLSS: monomials of degrees ``--degrees`` (default 2 3) in the states only,
   in the state equation only (E, no F): 64 parameters for n=3. As in the
   example the 4 periods are *averaged* into one period (``Signal.average``)
   and the model is fitted to that single 8192-sample period, each simulation
   being preceded by one full prepended period (transient vector
   ``T1 = [8192, 0]``) that is dropped from the error. Unit weighting in the
   time domain (the example's default), pyvib's own Levenberg-Marquardt
   (``PNLSS.optimize``, pyvib.common.lm) for ``--max-iter`` iterations.
4. Scores of the final iterate (the example instead picks the iterate that is
   best on the test multisine; we do not select on test data): rms error on
   the test multisine (``--val-periods`` periods simulated from rest, the last
   one kept) and on the sweep (from rest), in m and in dB (20 log10).

Timings (``time.perf_counter``, medians over ``--repeat`` calls where stated):
BLA, subspace, optional linear LM, one PNLSS Jacobian (``PNLSS.jacobian`` at
the fitted parameters, median), one model simulation on the training input
as the cost function does it (the averaged period with its prepended period,
16384 steps, median), the whole LM run and per iteration.

All progress output of pyvib goes to stderr; stdout holds one JSON object on
its only (hence last) line.
"""
import argparse
import contextlib
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

DEFAULT_DATA = Path(os.environ.get("SKLEARN_PNLSS_DATA", "/work/shared/data/bouc_wen"))
THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
NPP = 8192


def _parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pyvib-path", required=True,
                        help="folder holding the 'pyvib' package (prepended to sys.path)")
    parser.add_argument("--data-dir", default=str(DEFAULT_DATA),
                        help="folder with the official Bouc-Wen .mat files "
                             "(default: $SKLEARN_PNLSS_DATA or /work/shared/data/bouc_wen)")
    parser.add_argument("--degrees", type=int, nargs="+", default=[2, 3],
                        help="monomial degrees in the state equation (default: 2 3)")
    parser.add_argument("--n-states", type=int, default=3)
    parser.add_argument("--subspace-r", type=int, default=4,
                        help="subspace dimensioning parameter r (example: 4)")
    parser.add_argument("--max-iter", type=int, default=10,
                        help="Levenberg-Marquardt iterations for the PNLSS fit (default: 10)")
    parser.add_argument("--linear-lm-iter", type=int, default=0,
                        help="LM iterations on the linear model before PNLSS "
                             "(default: 0, as pyvib's example)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="calls for the median Jacobian and simulation times (default: 3)")
    parser.add_argument("--val-periods", type=int, default=3,
                        help="periods of the test multisine simulated from rest; "
                             "the last is scored (default: 3)")
    return parser.parse_args(argv)


def _git_commit(path):
    try:
        out = subprocess.run(["git", "-C", str(path), "rev-parse", "HEAD"],
                             capture_output=True, text=True, timeout=30, check=True)
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def _median_time(fun, repeat):
    times, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), times, out


def _load(data_dir, np, loadmat):
    data_dir = Path(data_dir)

    def vec(name, key):
        return np.asarray(loadmat(data_dir / name)[key], dtype=float).ravel()

    train = loadmat(data_dir / "train_multisine_official.mat")
    u = np.asarray(train["u"], dtype=float).ravel()
    y = np.asarray(train["y"], dtype=float).ravel()
    fs = float(np.asarray(train["fs"]).item())
    return {
        "u": u, "y": y, "fs": fs,
        "u_ms": vec("uval_multisine.mat", "uval_multisine"),
        "y_ms": vec("yval_multisine.mat", "yval_multisine"),
        "u_sw": vec("uval_sinesweep.mat", "uval_sinesweep"),
        "y_sw": vec("yval_sinesweep.mat", "yval_sinesweep"),
    }


def main(argv=None):
    args = _parse(argv)
    t_script = time.perf_counter()
    threads = {k: os.environ.get(k) for k in THREAD_VARS}
    print(f"thread settings: {threads}", file=sys.stderr)

    pyvib_path = Path(args.pyvib_path).resolve()
    sys.path.insert(0, str(pyvib_path))
    os.environ.setdefault("MPLBACKEND", "Agg")  # pyvib imports matplotlib

    import numpy as np
    import pyvib
    import scipy
    from pyvib.pnlss import PNLSS
    from pyvib.signal import Signal
    from pyvib.subspace import Subspace
    from scipy.io import loadmat

    log = contextlib.redirect_stdout(sys.stderr)  # keep stdout for the JSON line

    d = _load(args.data_dir, np, loadmat)
    fs = d["fs"]
    n_periods = d["u"].size // NPP
    if n_periods * NPP != d["u"].size or n_periods < 2:
        raise SystemExit(f"training record of {d['u'].size} samples is not whole {NPP}-sample periods")
    # drop period 1 (transient); the rest as pyvib's (npp, m, R, P) array
    u_per = d["u"].reshape(n_periods, NPP)[1:].T  # (npp, P)
    y_per = d["y"].reshape(n_periods, NPP)[1:].T
    P = u_per.shape[1]
    u_est = u_per[:, None, None, :]
    y_est = y_per[:, None, None, :]

    # excited lines (0-based FFT bins) read off the input spectrum
    spec = np.abs(np.fft.rfft(u_per[:, 0]))
    lines = np.flatnonzero(spec > 1e-6 * spec.max())
    lines = lines[lines > 0]

    # ---- linear start -------------------------------------------------
    with log:
        sig = Signal(u_est, y_est, fs=fs)
        sig.lines = lines
        t0 = time.perf_counter()
        sig.bla()
        t_bla = time.perf_counter() - t0
        um, ym = sig.average()

        linmodel = Subspace(sig)
        t0 = time.perf_counter()
        linmodel.estimate(n=args.n_states, r=args.subspace_r)
        t_subspace = time.perf_counter() - t0
        t_linear_lm = 0.0
        if args.linear_lm_iter > 0:
            weight = False
            if sig.covGn is not None:
                from pyvib.common import weightfcn
                weight = weightfcn(sig.covGn)
            t0 = time.perf_counter()
            linmodel.optimize(weight=weight, nmax=args.linear_lm_iter, info=2)
            t_linear_lm = time.perf_counter() - t0
    t_linear = t_bla + t_subspace + t_linear_lm

    # ---- PNLSS set-up ----------------------------------------------------
    with log:
        t0 = time.perf_counter()
        model = PNLSS(linmodel)
        model.transient(np.array([NPP, 0]))  # one period prepended to the one (averaged) realisation
        model.nlterms("x", list(args.degrees), "statesonly")
        t_setup = time.perf_counter() - t0
        theta_lin = model.flatten()
        n_params = int(theta_lin.size)

        # linear-model training error on the averaged period (steady state)
        _, y0, _ = model.simulate(um)
        rms_train_lin = float(np.sqrt(np.mean((ym - y0) ** 2)))

        # ---- Levenberg-Marquardt -------------------------------------------
        t0 = time.perf_counter()
        model.optimize(weight=False, nmax=args.max_iter, info=2)
        t_lm = time.perf_counter() - t0
        res = model.res
        n_iter = int(res["niter"])
        theta = model.flatten()

        # ---- kernel timings at the final parameters ------------------------
        # (the simulation also leaves the states of theta in the model, which
        # the Jacobian reads)
        t_sim, t_sim_all, (_, y_fit, _) = _median_time(lambda: model.simulate(um), args.repeat)
        rms_train = float(np.sqrt(np.mean((ym - y_fit) ** 2)))
        t_jac, t_jac_all, jac = _median_time(lambda: model.jacobian(theta, weight=False), args.repeat)

        # ---- test data --------------------------------------------------------
        k = max(1, args.val_periods)
        t0 = time.perf_counter()
        _, y_ms_sim, _ = model.simulate(np.tile(d["u_ms"], k)[:, None], T1=0)
        t_sim_ms = time.perf_counter() - t0
        e_ms = d["y_ms"] - y_ms_sim[-d["u_ms"].size:, 0]
        t0 = time.perf_counter()
        _, y_sw_sim, _ = model.simulate(d["u_sw"][:, None], T1=0)
        t_sim_sw = time.perf_counter() - t0
        e_sw = d["y_sw"] - y_sw_sim[:, 0]

    rms_ms = float(np.sqrt(np.mean(e_ms ** 2)))
    rms_sw = float(np.sqrt(np.mean(e_sw ** 2)))

    def db(x):
        return float(20 * np.log10(x)) if np.isfinite(x) and x > 0 else None

    result = {
        "peer": "pyvib",
        "version": getattr(pyvib, "__version__", None),
        "commit": _git_commit(pyvib_path),
        "pyvib_path": str(pyvib_path),
        "n_states": args.n_states,
        "degrees": list(args.degrees),
        "structure": "statesonly, state equation only (E), F empty",
        "n_params": n_params,
        "n_iter": n_iter,
        "max_iter": args.max_iter,
        "lm_status": res.get("message"),
        "lm_nfev": int(res["nfev"]),
        "t_bla_s": t_bla,
        "t_subspace_s": t_subspace,
        "t_linear_lm_s": t_linear_lm,
        "linear_lm_iter": args.linear_lm_iter,
        "t_linear_s": t_linear,
        "t_pnlss_setup_s": t_setup,
        "t_jacobian_s": t_jac,
        "t_jacobian_all_s": t_jac_all,
        "jacobian_shape": list(jac.shape),
        "t_simulation_s": t_sim,
        "t_simulation_all_s": t_sim_all,
        "simulation_samples": int(um.shape[0] + NPP),
        "t_lm_total_s": t_lm,
        "t_per_iter_s": t_lm / n_iter if n_iter else None,
        "t_total_s": t_linear + t_setup + t_lm,
        "t_sim_multisine_s": t_sim_ms,
        "t_sim_sweep_s": t_sim_sw,
        "t_script_s": time.perf_counter() - t_script,
        "rms_train_linear_m": rms_train_lin,
        "db_train_linear": db(rms_train_lin),
        "rms_train_m": rms_train,
        "db_train": db(rms_train),
        "rms_multisine_m": rms_ms,
        "db_multisine": db(rms_ms),
        "rms_sweep_m": rms_sw,
        "db_sweep": db(rms_sw),
        "val_periods": k,
        "n_lines": int(lines.size),
        "periods_used": f"2-{n_periods} of {n_periods} ({P} periods, 1 realisation)",
        "averaged_periods": True,
        "n_samples_fit": int(um.shape[0]),
        "transient": f"{NPP} samples (one period) prepended per realisation, T1=[{NPP}, 0]",
        "weighting": "none (time domain, unit weight)",
        "threads": threads,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "machine": platform.machine(),
        "processor": platform.processor() or None,
    }
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
