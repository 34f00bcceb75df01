"""
=====================================================
Detecting odd and even nonlinearities with multisines
=====================================================

A random-odd multisine excites only odd DFT lines, and in every group of
three consecutive odd lines leaves one out at random. A linear system
answers at the excited lines only. An *odd* nonlinearity (``f(-x) = -f(x)``,
e.g. a cubic spring or the Bouc-Wen hysteresis) mixes odd numbers of odd
lines and so lands on odd lines, among them the left-out *odd detection
lines*. An *even* nonlinearity (e.g. a quadratic term) mixes even numbers of
odd lines and lands on the never-excited *even lines*. A look at the output
spectrum at these three kinds of lines tells, before any modelling, whether
a nonlinear model is needed and which kind.

We compare three systems driven by the same random-odd multisines: the
linear part of the Bouc-Wen benchmark, the same linear system seen through
a sensor with a quadratic term (even), and the Bouc-Wen benchmark itself
(odd).
"""

# %%
# Excitation
# ----------
# Two realisations (independent phases, same lines) of two periods each, so
# the estimator can separate noise (spread over periods) from nonlinear
# distortion (spread over realisations). A short period keeps the example
# fast; the line spacing is still 750 / 4096 = 0.18 Hz.
import matplotlib.pyplot as plt
import numpy as np

from sklearn_pnlss import BLAEstimator
from sklearn_pnlss.datasets import simulate_bouc_wen
from sklearn_pnlss.physics import Oscillator
from sklearn_pnlss.signals import multisine

fs, period, n_periods = 750.0, 4096, 2
X, lines = multisine(period, fs=fs, f_band=(5.0, 150.0), rms=50.0, kind="random_odd",
                     n_realizations=2, random_state=0)
print(f"{lines.size} excited lines between {lines[0] * fs / period:.2f} and "
      f"{lines[-1] * fs / period:.2f} Hz")

# %%
# Three systems
# -------------
# Each simulator returns one steady-state period; the periods are repeated
# and a little white measurement noise is added to every sample so that the
# estimator has a noise floor to compare with.
linear = Oscillator(2.0, 10.0, 1e5)  # m, c, k + alpha of the benchmark


def linear_system(u):
    return linear.simulate(u, fs=fs, periodic=True)


def quadratic_sensor(u):
    # y + q y^2 with q y about 0.6 % at the rms of y: a weak even
    # nonlinearity in the measurement, the dynamics stay linear.
    y = linear.simulate(u, fs=fs, periodic=True)
    return y + 3.0 * y**2


def bouc_wen(u):
    return simulate_bouc_wen(u, periodic=True)


systems = {
    "linear": linear_system,
    "even: quadratic output": quadratic_sensor,
    "odd: Bouc-Wen": bouc_wen,
}

rng = np.random.RandomState(1)
noise_rms = 1e-7  # m
X_train = np.tile(X, (1, n_periods, 1))
models = {}
for name, system in systems.items():
    # A handful of signals: the loop is over realisations, not samples.
    y = np.stack([np.tile(system(x[:, 0]), n_periods) for x in X])[..., None]
    y = y + noise_rms * rng.standard_normal(y.shape)
    models[name] = BLAEstimator(n_states=2, period=period, fs=fs, lines=lines).fit(X_train, y)

# %%
# Distortion levels
# -----------------
# ``distortion_levels_`` averages the output power (dB, per DFT bin of one
# period) over the excited lines and over the odd and even detection lines
# inside the excited band, next to the noise level. The linear system's
# detection lines sit at the noise; the quadratic sensor lifts the even
# lines only, the Bouc-Wen system the odd ones only.
print(f"{'system':24s}" + "".join(f"{k:>10s}" for k in ("excited", "odd", "even", "noise")))
for name, model in models.items():
    levels = model.distortion_levels_
    print(f"{name:24s}" + "".join(f"{levels[k]:10.1f}" for k in ("excited", "odd", "even", "noise")))

# %%
# Output spectra
# --------------
# The period-averaged output power at every DFT bin, coloured by line kind
# (``line_kind_``: 1 excited, 2 non-excited odd, 3 even), with the noise
# level. Above 150 Hz nothing is excited, so every odd or even bin there is a
# detection line: the harmonics of the nonlinearity show up clearly.
fig, axes = plt.subplots(len(models), 1, figsize=(8, 8), sharex=True, sharey=True)
for ax, (name, model) in zip(axes, models.items()):
    f = np.arange(model.line_kind_.size) * fs / period
    level = 10 * np.log10(model.output_level_[:, 0])
    for kind, label, style in ((1, "excited", "k."), (2, "odd detection", "C3."),
                               (3, "even", "C0.")):
        sel = model.line_kind_ == kind
        ax.plot(f[sel], level[sel], style, ms=2, label=label)
    ax.plot(f, 10 * np.log10(model.noise_level_[:, 0]), "0.6", lw=0.5, label="noise")
    ax.set_title(name)
    ax.set_ylabel("output (dB)")
    ax.grid(alpha=0.3)
axes[0].legend(markerscale=4, fontsize=8, loc="upper right")
axes[-1].set_xlabel("frequency (Hz)")
axes[-1].set_xlim(0, 300)
plt.tight_layout()

plt.show()
