"""
=====================================================================
Measured data: the F-16 ground vibration test
=====================================================================

Measurements of a real structure instead of a simulation: the F-16 ground
vibration test benchmark (Noel and Schoukens, 2017). A full-scale F-16 with
two dummy payloads at its wing tips was excited by a shaker under the right
wing; the input is the measured force, the outputs are three accelerations
(at the shaker, on the right wing next to the payload interface, on the
payload). The bolted wing-to-payload interface adds friction and clearance.
About ten lightly damped modes lie in the excited band of 2-15 Hz.

This example fits the best linear approximation (BLA) of the level-3 full
multisine (36.8 N rms, one realisation of 9 periods of 8192 samples at
400 Hz; the first period is a transient and is dropped), linear models of
growing order, a PNLSS model and a decoupled one, and scores them on the
benchmark's test level 2 (24.6 N rms). With the files it runs for a few
minutes (most of it the two nonlinear fits).

The data are not shipped with the library. Download ``F16GVT_Files.zip``
from nonlinearbenchmark.org, unpack it and set the environment variable
``SKLEARN_PNLSS_F16_DATA`` to its folder (or to ``BenchmarkData`` in it).
Without the files the example says so and stops short of the figures: the
documentation is built without them.
"""

# %%
# The data
# --------
# :func:`~sklearn_pnlss.datasets.load_f16` puts the steady-state periods in
# the library's layout: ``X`` of shape (1, 65536, 1) and ``y`` of shape
# (1, 65536, 3), with the test level as ``X_val, y_val``.
import os
import time

import matplotlib.pyplot as plt
import numpy as np

from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.datasets import load_f16
from sklearn_pnlss.plotting import plot_bla

try:
    data = load_f16(os.environ.get("SKLEARN_PNLSS_F16_DATA"), level=3)
except FileNotFoundError as missing:
    data = None
    print(f"F-16 benchmark files not available, nothing more to show:\n{missing}")
else:
    print(f"training: X {data.X.shape}, y {data.y.shape}, {data.lines.size} excited lines "
          f"({data.lines[0] * data.fs / data.period:.2f}-{data.lines[-1] * data.fs / data.period:.2f} Hz)")
    print(f"test level {data.validation_level}: X {data.X_val.shape}")


def relative_error(model, X, y):
    """rms simulation error per output, relative to the output's rms."""
    return np.sqrt(np.mean((model.predict(X) - y) ** 2, axis=(0, 1)) / np.mean(y**2, axis=(0, 1)))


# %%
# Best linear approximation
# -------------------------
# With a single realisation the spread over the 8 periods measures the noise
# (about 0.3 % of the FRF); the stochastic nonlinear distortion of the
# multisine stays in the BLA itself. Outside the excited band, the output
# power at the lines the multisine leaves out shows the nonlinearity:
# 33-50 dB below the excited lines, yet 20-30 dB above the noise.
if data is not None:
    start = time.perf_counter()
    bla = BLAEstimator(16, period=data.period, fs=data.fs).fit(data.X, data.y)
    bla_seconds = time.perf_counter() - start
    print(f"BLA and a 16-state model in {bla_seconds:.1f} s")

    fig, axes = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for output, ax in enumerate(axes):
        plot_bla(bla, ax=ax, output=output)
        ax.set_title(data.output_names[output])
        ax.set_xlabel("")
    axes[-1].set_xlabel("frequency (Hz)")
    fig.tight_layout()

    f = np.arange(bla.output_level_.shape[0]) * data.fs / data.period
    shown = f < 40
    excited = shown & (bla.line_kind_ == 1)
    other = shown & (bla.line_kind_ > 1)
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(f[other], 10 * np.log10(bla.output_level_[other, 1]), "C3.", ms=2, label="lines not excited")
    ax.plot(f[excited], 10 * np.log10(bla.output_level_[excited, 1]), "k.", ms=3, label="excited lines")
    ax.plot(f[shown], 10 * np.log10(bla.noise_level_[shown, 1]), "C0", lw=0.6, label="noise")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("output power (dB)")
    ax.set_title(f"Output spectrum: {data.output_names[1]}")
    ax.legend(fontsize=8)

# %%
# Linear models of growing order
# ------------------------------
# The model FRF follows the BLA better with more states, until what is left
# is the line-to-line distortion of the single realisation. On the test level
# every linear model is as far off as the level-3 BLA itself: the structure's
# linearisation depends on the level (the torsion mode near 7.3 Hz shifts).
if data is not None:
    print(" n   FRF error   training error (per output)   test error (per output)   time")
    for n in (6, 10, 16):
        start = time.perf_counter()
        model = bla if n == 16 else BLAEstimator(n, period=data.period, fs=data.fs).fit(data.X, data.y)
        seconds = bla_seconds if n == 16 else time.perf_counter() - start
        frf = np.linalg.norm(model.frf_model_ - model.frf_) / np.linalg.norm(model.frf_)
        train = np.array2string(relative_error(model, data.X, data.y), precision=3)
        test = np.array2string(relative_error(model, data.X_val, data.y_val), precision=3)
        print(f"{n:2d}   {frf:9.3f}   {train:>27s}   {test:>23s}   {seconds:4.1f} s")

# %%
# PNLSS and decoupled PNLSS
# -------------------------
# Ten states. The PNLSS model has all monomials of degrees 2 and 3 in the
# states (2,750 coefficients in the state equation) and starts from the
# 10-state linear model; the decoupled model replaces them by two cubic
# branches of linear combinations of the states and the input (48
# coefficients) and starts from the PNLSS model. Each gets ten
# Levenberg-Marquardt iterations on the period-averaged signal. The stages
# are fitted one after the other as a ``Pipeline`` would (each stage's
# ``transform`` hands its fitted model to the next), to time each.
#
# Measured: the PNLSS model lowers the training error most next to the
# interface but gains little on the test level; the decoupled model, with
# fewer parameters, fits the training data a little less well and the test
# level clearly better (23 % instead of 39-40 % on the accelerations next to
# the interface).
if data is not None:
    from sklearn_pnlss import DecoupledPNLSSRegressor

    stages = [
        ("linear", BLAEstimator(10, period=data.period, fs=data.fs)),
        ("PNLSS", PNLSSRegressor(10, degrees=(2, 3), variables="states", period=data.period, max_iter=10)),
        ("decoupled", DecoupledPNLSSRegressor(10, n_branches=2, degree=3, period=data.period, n_init=2,
                                              max_iter=10, random_state=0)),
    ]
    X = data.X
    for name, model in stages:
        start = time.perf_counter()
        model.fit(X, data.y)
        seconds = time.perf_counter() - start
        X = model.transform(X)
        n_nonlinear = getattr(model, "n_nonlinear_params_", 0)
        print(f"{name:9s} {n_nonlinear:5d} nonlinear coefficients, fit in {seconds:5.1f} s: "
              f"training {np.array2string(relative_error(model, data.X, data.y), precision=3)}, "
              f"test {np.array2string(relative_error(model, data.X_val, data.y_val), precision=3)}")

# %%
# What does not work yet
# ----------------------
# - **Another level.** Fitted on level 3 alone, even the decoupled model
#   stays 21-23 % off on test level 2 (the linear models 30-44 %): the joint's
#   friction and clearance act differently at each level, and one level
#   does not show that. Fitting levels 1, 3, 5 and 7 together (the
#   benchmark's training set) is not shown here.
# - **Many states.** The full PNLSS polynomial grows with the cube of the
#   state count: 2,750 coefficients at 10 states (ten iterations take about a
#   minute), 15,232 at 16. Past ten states, only the decoupled form is
#   practical.
# - **Several outputs.** The three accelerations share one cost with equal
#   weights; the acceleration at the shaker gains least (training error 15 %
#   to 11 %, against 12 % to 3-6 % next to the interface). Weighting each
#   output by its noise (``weighting="noise"``) is not tried here.
plt.show()
