"""
==========================================================
Model selection with a Pipeline and GridSearchCV
==========================================================

The decoupled PNLSS model has two structural choices: the number of
branches ``r`` and their degree ``d``. Selecting them is a grid search,
done here with scikit-learn's own tools:

* a ``Pipeline`` of the three estimators, BLA -> full PNLSS -> decoupled
  PNLSS, where each stage starts from the one before it, and whose
  ``memory`` caches the first two stages so that they are fitted once for
  the whole grid;
* ``GridSearchCV`` over the decoupled stage's parameters, scoring each
  candidate on *held-out signals* (never used for fitting) with
  :func:`~sklearn_pnlss.model_selection.held_out_signals` and the per-signal
  dB scorer :func:`~sklearn_pnlss.model_selection.mean_rms_db_scorer`;
* a second metric, :func:`~sklearn_pnlss.model_selection.n_nonlinear_params_scorer`,
  records each candidate's number of parameters, to plot the error against
  the model size.

The grid is small to keep the example fast; the seed paper's grid (6
branch counts x 10 degrees x 5 starts) runs the same way.
"""

# %%
# Training, validation and selection signals
# ------------------------------------------
# Training: two realisations of two steady-state periods at 55 N rms.
# Validation (the best iterate and the best start of each fit): the last
# period of a third realisation. Selection: a fourth multisine period and a
# short swept sine from rest, both simulated with the benchmark's simulator,
# so that the benchmark's own test signals stay untouched until the end.
import tempfile

import matplotlib.pyplot as plt
import numpy as np
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV
from sklearn.pipeline import Pipeline

from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor
from sklearn_pnlss.datasets import make_bouc_wen, simulate_bouc_wen
from sklearn_pnlss.metrics import rms_error
from sklearn_pnlss.model_selection import held_out_signals, mean_rms_db_scorer, n_nonlinear_params_scorer
from sklearn_pnlss.plotting import plot_branches, plot_grid_search
from sklearn_pnlss.signals import swept_sine

data = make_bouc_wen(n_realizations=4, n_periods=2, rms=55.0, random_state=0, n_jobs=2)
P, fs = data.period, data.fs
X_train, y_train = data.X_train[:2], data.y_train[:2]
X_val, y_val = data.X_train[2:3, P:], data.y_train[2:3, P:]
u_sweep = swept_sine(15000, fs=fs, f_start=20.0, f_stop=50.0, amplitude=40.0)
y_sweep = simulate_bouc_wen(u_sweep, periodic=False)
X_sel = [data.X_train[3, P:], u_sweep[:, None]]
y_sel = [data.y_train[3, P:], y_sweep[:, None]]

# All signals in one list, with the one split "train on the first two, score
# on the held-out ones".
X, y, cv = held_out_signals(X_train, y_train, X_sel, y_sel)

# %%
# The pipeline and the search
# ---------------------------
# Each decoupled candidate gets one start (``n_init=1``) and few iterations
# here. ``refit=False``: GridSearchCV would refit on *all* the signals it
# was given, the held-out ones included; the best candidate is refitted on
# the training signals below instead. The validation signals reach the
# decoupled stage's ``fit`` as ``decoupled__X_val`` / ``decoupled__y_val``.
cache = tempfile.TemporaryDirectory()
pipe = Pipeline([
    ("bla", BLAEstimator(n_states=3, period=P, fs=fs)),
    ("pnlss", PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=P, max_iter=20)),
    ("decoupled", DecoupledPNLSSRegressor(3, period=P, n_init=1, max_iter=15, random_state=0)),
], memory=cache.name)
grid = {"decoupled__n_branches": [1, 2, 3], "decoupled__degree": [3, 5, 7]}
search = GridSearchCV(
    pipe, grid, cv=cv, refit=False, n_jobs=2, error_score=np.nan,
    scoring={"db": mean_rms_db_scorer, "n_nonlinear_params": n_nonlinear_params_scorer},
)
search.fit(X, y, decoupled__X_val=X_val, decoupled__y_val=y_val)

results = search.cv_results_
for params, score, n_par in zip(results["params"], results["mean_test_db"], results["mean_test_n_nonlinear_params"]):
    print(f"r = {params['decoupled__n_branches']}, d = {params['decoupled__degree']}: "
          f"{-score:7.2f} dB, {int(n_par):3d} nonlinear parameters")

# %%
# Error against degree, one line per branch count
# -----------------------------------------------
# The mean over the two selection signals of each signal's rms error in dB.
# More branches lower the error at every degree: one branch cannot carry
# the hysteresis, whatever its degree. With one start and fifteen iterations
# per candidate the differences stay within a few dB; the paper's grid,
# with five starts and full fits, separates the candidates further.
ax = plot_grid_search(search, "decoupled__degree", group="decoupled__n_branches", score="db")
ax.set_title("Selection error against branch degree")
plt.tight_layout()

# %%
# Refit the selected model and test it
# ------------------------------------
# The best candidate by the selection error is refitted on the training
# signals, passed as the search's training split (``X[:2]``) so that the
# pipeline's cache serves the BLA and full PNLSS stages. Only then is it
# scored on the benchmark's test multisine and sweep.
best = int(np.nanargmax(results["mean_test_db"]))
best_params = results["params"][best]
model = clone(pipe).set_params(**best_params)
model.fit(X[:2], y[:2], decoupled__X_val=X_val, decoupled__y_val=y_val)
print("selected:", best_params)
for name, Xt, yt in (("multisine", data.X_test_multisine, data.y_test_multisine),
                     ("sweep", data.X_test_sweep, data.y_test_sweep)):
    print(f"test {name}: {rms_error(yt, model.predict(Xt), db=True):.2f} dB")
print(model[-1].summary())

# %%
# Error against the number of parameters
# --------------------------------------
# The same candidates against their number of nonlinear parameters,
# ``(2 n + m + d) r`` with ``n = 3`` states and ``m = 1`` input. The star is
# the full PNLSS stage (90 nonlinear parameters) every candidate started
# from, scored on the same signals (``model[:2]``, the pipeline up to it).
# Every candidate carries on from it with a fraction of its parameters, and
# the best ones end several dB below it.
full = model[:2]
ax = plot_grid_search(search, "n_nonlinear_params", group="decoupled__n_branches", score="db")
ax.plot(full[-1].n_nonlinear_params_, -mean_rms_db_scorer(full, X_sel, y_sel), "k*", ms=14, label="full PNLSS")
ax.set_xscale("log")
ax.legend(fontsize=8)
ax.set_title("Selection error against model size")
plt.tight_layout()

# %%
# The branches of the selected model
# ----------------------------------
# Each branch ``g_l`` over the range its input ``z_l`` spanned in training,
# and the points where the model evaluates it on the test multisine. Points
# beyond the ends of the curve are where the test signal drives the model
# outside its training range: there the polynomial extrapolates, and the
# error grows (one reason to train at a slightly higher level than the
# test's).
axes = plot_branches(model[-1], data.X_test_multisine)
axes[0].figure.suptitle("Branches of the selected decoupled model")
plt.tight_layout()

cache.cleanup()
plt.show()
