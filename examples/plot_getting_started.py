"""
===============
Getting started
===============

The whole workflow on the Bouc-Wen hysteresis benchmark in a few lines:
simulate data, fit a linear model (the best linear approximation, BLA) and a
polynomial nonlinear state-space (PNLSS) model, score both on the test
signals, read a model's summary, export its linear part to SciPy, save it
and load it back.

Signals are 3-D arrays ``(n_signals, n_samples, n_channels)``: here one
input (a force in N) and one output (a displacement in m). With ``period``
set (in samples), a signal whose length is a whole number of periods is
taken as periodic steady state; any other signal starts from rest.
"""

# %%
# Data
# ----
# :func:`~sklearn_pnlss.datasets.make_bouc_wen` simulates the benchmark
# exactly as its official data were made: random-phase multisines (5-150 Hz,
# 8192 samples per period at 750 Hz) in steady state, with output noise,
# for training; a noiseless multisine period and the benchmark's swept sine
# (from rest) for testing. Two realisations of two periods are the least
# that separates noise from nonlinear distortion.
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from sklearn.pipeline import make_pipeline

from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.datasets import make_bouc_wen
from sklearn_pnlss.metrics import rms_error
from sklearn_pnlss.persistence import load, save
from sklearn_pnlss.plotting import plot_error_spectra, plot_time_errors

data = make_bouc_wen(n_realizations=2, n_periods=2, random_state=0)
P, fs = data.period, data.fs
print("training:", data.X_train.shape, " test multisine:", data.X_test_multisine.shape,
      " test sweep:", data.X_test_sweep.shape)

# %%
# A linear model
# --------------
# ``BLAEstimator`` estimates the BLA from the periodic data and fits a
# third-order discrete-time state-space model to it. ``score`` returns minus
# the rms simulation error in dB (higher is better).
bla = BLAEstimator(n_states=3, period=P, fs=fs).fit(data.X_train, data.y_train)
score = bla.score(data.X_test_multisine, data.y_test_multisine)
print(f"BLA score {score:.2f}: the rms error on the test multisine is {-score:.2f} dB (re 1 m)")

# %%
# A nonlinear model
# -----------------
# A ``Pipeline`` hands the fitted BLA to the PNLSS model as its start. The
# PNLSS model adds all monomials of degrees 2 and 3 in the states to the
# state equation (64 parameters in all) and fits everything by
# Levenberg-Marquardt on the simulation error. Few iterations keep this
# example fast; more lower the error further.
model = make_pipeline(
    BLAEstimator(n_states=3, period=P, fs=fs),
    PNLSSRegressor(n_states=3, degrees=(2, 3), variables="states", period=P, max_iter=20),
)
model.fit(data.X_train, data.y_train)

# %%
# Scores on the two test signals
# ------------------------------
# ``predict`` simulates: the multisine (one whole period) in steady state,
# the sweep from rest. Errors are rms in metres and in dB (``20 log10``).
for name, X, y in (("multisine", data.X_test_multisine, data.y_test_multisine),
                   ("sweep", data.X_test_sweep, data.y_test_sweep)):
    for label, est in (("BLA", bla), ("PNLSS", model)):
        y_pred = est.predict(X)
        print(f"{name:9s} {label:5s}: {rms_error(y, y_pred):.3e} m ({rms_error(y, y_pred, db=True):6.2f} dB)")

# %%
# What the model is
# -----------------
# ``summary()`` gives the parameter counts, the poles of the linear part
# (as natural frequencies and damping ratios, in Hz since the BLA stage knew
# ``fs``) and the figures of the fit; with signals, also the error on them.
pnlss = model[-1]
print(pnlss.summary(data.X_test_multisine, data.y_test_multisine))

# %%
# The linear part as a SciPy system, e.g. for a Bode plot or a controller
# design. ``to_statespace()`` returns a discrete-time
# :class:`scipy.signal.StateSpace` with ``dt = 1 / fs``.
linear_part = pnlss.to_statespace()
print(linear_part)

# %%
# Save and load
# -------------
# :func:`~sklearn_pnlss.persistence.save` writes the fitted pipeline with
# joblib, together with the library's version; :func:`~sklearn_pnlss.persistence.load`
# refuses, with a clear message, a file written by an incompatible version.
with tempfile.TemporaryDirectory() as folder:
    path = save(model, Path(folder) / "bouc_wen_pnlss.joblib")
    reloaded = load(path)
same = np.array_equal(reloaded.predict(data.X_test_sweep), model.predict(data.X_test_sweep))
print(f"reloaded model predicts identically: {same}")

# %%
# Figures
# -------
# The BLA's FRF with its noise and nonlinear-distortion levels, the spectra
# of the output and of both models' errors on the test multisine, and the
# errors over time on the sweep: the PNLSS model removes most of the error
# the linear model makes around the resonance.
ax = bla.plot()
ax.set_xlim(0, 160)
plt.tight_layout()

predictions = {"BLA": bla.predict(data.X_test_multisine)[0, :, 0],
               "PNLSS": model.predict(data.X_test_multisine)[0, :, 0]}
ax = plot_error_spectra(data.y_test_multisine[0, :, 0], predictions, fs=fs)
ax.set_title("Test multisine: output and error spectra")
plt.tight_layout()

predictions = {"BLA": bla.predict(data.X_test_sweep)[0, :, 0],
               "PNLSS": model.predict(data.X_test_sweep)[0, :, 0]}
fig, ax = plt.subplots(figsize=(9, 4))
plot_time_errors(data.y_test_sweep[0, :, 0], predictions, fs=fs, ax=ax)
scale = max(np.max(np.abs(data.y_test_sweep[0, :, 0] - p)) for p in predictions.values())
ax.set_ylim(-1.2 * scale, 1.2 * scale)
ax.set_ylabel("displacement error (m)")
ax.set_title("Test sweep: simulation errors")
plt.tight_layout()

plt.show()
