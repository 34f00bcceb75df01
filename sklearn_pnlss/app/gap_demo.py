"""The main job's diagnosis demo (``python -m sklearn_pnlss --gap-demo``):
what a linear simulator of the Bouc-Wen benchmark structure misses (its
hysteresis)."""
import json
import time
from pathlib import Path

import numpy as np

__all__ = ["run_gap_demo"]


def run_gap_demo(out_dir=None, *, n_samples=2048, n_realizations=2, n_periods=2, n_jobs=2,
                 random_state=0, plot=True, progress=False):
    """Diagnose the gap between a mass-spring-damper simulator and data
    from the Bouc-Wen benchmark system (the same structure with hysteresis).

    Parameters
    ----------
    out_dir : str or Path, default=None
        Folder for ``gap_report.json``, ``gap_report.txt`` and
        ``gap_report.png``; None writes nothing.
    n_samples : int, default=2048
        Samples per multisine period at 750 Hz.
    n_realizations, n_periods : int, default=2
        Training realisations and periods per realisation.
    n_jobs : int, default=2
        Candidates fitted in parallel.
    random_state : int, default=0
    plot : bool, default=True
        Write the report's figure (needs matplotlib).
    progress : bool, default=False
        Print each candidate as it is fitted (the diagnosis's ``verbose``).

    Returns
    -------
    report : GapReport
    seconds : float
        Wall time of the diagnosis (fit and report).
    """
    from ..datasets import make_bouc_wen, simulate_bouc_wen
    from ..gap import GapDiagnosis
    from ..physics import Oscillator
    from ..signals import swept_sine

    data = make_bouc_wen(n_realizations=n_realizations + 1, n_periods=n_periods, n_samples=n_samples,
                         random_state=random_state, n_jobs=n_jobs)
    # Not a multiple of the period: a signal of whole periods would be taken
    # as periodic steady state, and the sweep starts from rest.
    sweep = swept_sine(3 * n_samples - n_samples // 16, fs=data.fs, f_start=15.0, f_stop=60.0, amplitude=20.0)
    y_sweep = simulate_bouc_wen(sweep, periodic=False, noise_rms=8e-6, random_state=random_state + 1)
    X_val = [data.X_train[-1, :n_samples], sweep[:, None]]
    y_val = [data.y_train[-1, :n_samples], y_sweep[:, None]]
    start = time.perf_counter()
    diagnosis = GapDiagnosis(Oscillator(2.0, 10.0, 5e4), fs=data.fs, period=n_samples, n_jobs=n_jobs,
                             random_state=random_state, verbose=int(progress))
    report = diagnosis.fit(data.X_train[:-1], data.y_train[:-1]).report(X_val, y_val)
    seconds = time.perf_counter() - start
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        summary = dict(report.to_dict(), seconds=seconds)
        (out / "gap_report.json").write_text(json.dumps(summary, indent=1))
        (out / "gap_report.txt").write_text(str(report) + "\n")
        if plot:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            fig = report.plot()
            fig.savefig(out / "gap_report.png", dpi=110, bbox_inches="tight")
            plt.close(fig)
    return report, float(np.round(seconds, 2))
