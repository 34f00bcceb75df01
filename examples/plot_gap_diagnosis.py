"""
Sim-to-real gap diagnosis: what is my simulator missing?
=========================================================

An engineer has a physical simulator of a structure, here a single mass on a
spring and a viscous damper (``m = 2 kg, c = 10 N s/m, k = 5e4 N/m``), and
measurements of the real structure.  The real structure is the Bouc-Wen
hysteresis benchmark: the same mass, spring and damper *plus* a hysteretic
force that the simulator does not have.

:class:`~sklearn_pnlss.gap.GapDiagnosis` answers three questions:

1. **Where** does the simulator miss the measurements?  In frequency, against
   amplitude, over the (displacement, velocity) plane, and over time.
2. **Which** unmodelled effect causes it?  Every built-in candidate
   (hysteresis, cubic or quadratic stiffness, friction, quadratic damping,
   backlash, input saturation, input delay, a second mode, stiffness drift)
   and a plain refit of the nominal parameters (``recalibration``) is added
   to the simulator, fitted to the training measurements, and scored on
   validation measurements that were never used for fitting.
3. **How far** does the gap shrink once the effect is added, against the
   noise floor that no model can go below?

The data are small so that the example runs in seconds; a real diagnosis
uses full-length records (see ``benchmarks/gap_withheld.py``).
"""

# %%
# Measurements of the "real" structure
# ------------------------------------
# Two random-phase multisine realisations of two periods each (2048 samples
# at 750 Hz) for training, measured with the benchmark's noise; for
# validation, a new multisine period and a short swept sine from rest.
import matplotlib.pyplot as plt

from sklearn_pnlss.datasets import make_bouc_wen, simulate_bouc_wen
from sklearn_pnlss.gap import GapDiagnosis
from sklearn_pnlss.physics import Oscillator
from sklearn_pnlss.signals import swept_sine

data = make_bouc_wen(n_realizations=3, n_periods=2, n_samples=2048, random_state=0)
X_train, y_train = data.X_train[:2], data.y_train[:2]
sweep = swept_sine(6000, fs=data.fs, f_start=15.0, f_stop=60.0, amplitude=20.0)
y_sweep = simulate_bouc_wen(sweep, periodic=False, noise_rms=8e-6, random_state=1)
X_val = [data.X_train[2, :2048], sweep[:, None]]
y_val = [data.y_train[2, :2048], y_sweep[:, None]]

# %%
# The diagnosis
# -------------
# ``fit`` fits every candidate to the training signals by simulation error
# (and a black-box decoupled PNLSS model of the same data, as a yardstick);
# ``report`` scores them on the validation signals.
nominal = Oscillator(2.0, 10.0, 5e4)
diagnosis = GapDiagnosis(nominal, fs=data.fs, period=2048, n_jobs=2, random_state=0)
diagnosis.fit(X_train, y_train)
report = diagnosis.report(X_val, y_val)
print(report)

# %%
# The verdict is hysteresis, with its fitted Bouc-Wen parameters; the
# ranking shows how much each candidate closes of the gap's excess over the
# noise floor.  ``recalibration`` (a stiffer spring) closes part of it: the
# hysteretic force is a spring plus a loop, so refitting ``k`` mimics the
# spring but not the loop.
best = report.ranking[0]
print(best.name, {k: round(float(v), 3) for k, v in best.params.items()})

# %%
# Figures
# -------
# The candidates' validation gaps against the nominal gap and the noise
# floor; the gap spectrum with its significant lines, the noise and the
# nonlinear distortion level; the gap against amplitude; the missing force
# over the (displacement, velocity) plane (a hysteresis loop shows as a force
# that depends on the direction of motion, i.e. on the sign of the
# velocity); the gap along the sweep; and the branches of the black box.
report.plot()
plt.show()

# %%
# The report as data
# ------------------
# ``to_dict()`` gives everything in plain types, ready for ``json.dump``.
summary = report.to_dict()
print(summary["best_effect"], round(summary["gap_db"], 1), "dB ->",
      round(summary["ranking"][0]["gap_after_db"], 1), "dB")
