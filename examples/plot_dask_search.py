"""
=====================================
Running the search on a Dask cluster
=====================================

A selection grid of decoupled PNLSS models is hundreds of independent fits:
work for a cluster. ``GridSearchCV`` runs its fits through joblib, and
joblib hands them to Dask with ``joblib.parallel_backend("dask")``; nothing
else changes. This example starts a small ``LocalCluster`` on this machine;
on a real cluster, connect the client to its scheduler instead
(``Client("tcp://scheduler-address:8786")``) and the same code spreads the
grid over all its workers.

The workers here are threads of this process (``processes=False``): the
library's compiled kernels release the GIL, so threads run in parallel,
and the example starts in a second. Worker processes, or remote machines,
need the library installed where they run.
"""

# %%
# Data and the search, as in the selection example
# ------------------------------------------------
# Two training realisations, a validation period (best iterate of each
# fit), and held-out selection signals: a fourth multisine period and a
# short swept sine. The Pipeline's memory caches the BLA and full PNLSS
# stages: on a cluster, point it at a folder all workers share. (Small
# settings keep the example fast: few iterations, one start per candidate.)
import tempfile

import joblib
import matplotlib.pyplot as plt
import numpy as np
from dask.distributed import Client, LocalCluster
from sklearn.model_selection import GridSearchCV
from sklearn.pipeline import Pipeline

from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor
from sklearn_pnlss.datasets import make_bouc_wen, simulate_bouc_wen
from sklearn_pnlss.model_selection import held_out_signals, mean_rms_db_scorer
from sklearn_pnlss.plotting import plot_grid_search
from sklearn_pnlss.signals import swept_sine

data = make_bouc_wen(n_realizations=4, n_periods=2, rms=55.0, random_state=1, n_jobs=2)
P, fs = data.period, data.fs
X_val, y_val = data.X_train[2:3, P:], data.y_train[2:3, P:]
u_sweep = swept_sine(15000, fs=fs, f_start=20.0, f_stop=50.0, amplitude=40.0)
X, y, cv = held_out_signals(data.X_train[:2], data.y_train[:2],
                            [data.X_train[3, P:], u_sweep[:, None]],
                            [data.y_train[3, P:], simulate_bouc_wen(u_sweep, periodic=False)[:, None]])

cache = tempfile.TemporaryDirectory()
pipe = Pipeline([
    ("bla", BLAEstimator(n_states=3, period=P, fs=fs)),
    ("pnlss", PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=P, max_iter=10)),
    ("decoupled", DecoupledPNLSSRegressor(3, period=P, n_init=1, max_iter=10, random_state=0)),
], memory=cache.name)
grid = {"decoupled__n_branches": [1, 3], "decoupled__degree": [3, 6]}
search = GridSearchCV(pipe, grid, cv=cv, scoring=mean_rms_db_scorer, refit=False, n_jobs=-1, error_score=np.nan)

# %%
# The cluster
# -----------
# Two single-threaded workers. ``n_jobs=-1`` in the search means "as many
# tasks at once as the cluster has worker threads". The dashboard link shows
# the tasks live while the search runs.
with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster, \
        Client(cluster) as client:
    print("dashboard:", client.dashboard_link)
    with joblib.parallel_backend("dask"):
        search.fit(X, y, decoupled__X_val=X_val, decoupled__y_val=y_val)
cache.cleanup()

results = search.cv_results_
for params, score, fit_time in zip(results["params"], results["mean_test_score"], results["mean_fit_time"]):
    print(f"r = {params['decoupled__n_branches']}, d = {params['decoupled__degree']}: "
          f"{-score:7.2f} dB, fitted in {fit_time:5.2f} s")

# %%
# Results
# -------
# The selection error of each candidate, as a map over the grid and as
# lines against the degree, and the time each fit took on its worker (the
# first fits also fitted the cached BLA and full PNLSS stages).
branches, degrees = grid["decoupled__n_branches"], grid["decoupled__degree"]
error = np.full((len(branches), len(degrees)), np.nan)
fit_time = np.full_like(error, np.nan)
for params, score, t in zip(results["params"], results["mean_test_score"], results["mean_fit_time"]):
    i, j = branches.index(params["decoupled__n_branches"]), degrees.index(params["decoupled__degree"])
    error[i, j], fit_time[i, j] = -score, t

fig, (ax_map, ax_line, ax_time) = plt.subplots(1, 3, figsize=(13, 3.8))
im = ax_map.imshow(error, origin="lower", cmap="viridis", aspect="auto")
ax_map.set_xticks(range(len(degrees)), [str(d) for d in degrees])
ax_map.set_yticks(range(len(branches)), [str(r) for r in branches])
ax_map.set_xlabel("degree d")
ax_map.set_ylabel("branches r")
for (i, j), value in np.ndenumerate(error):
    light = im.norm(value) > 0.5  # dark text on the light (yellow) end of the map
    ax_map.text(j, i, f"{value:.1f}", ha="center", va="center", color="k" if light else "w", fontsize=9)
fig.colorbar(im, ax=ax_map, label="rms error (dB)")
ax_map.set_title("Selection error")
plot_grid_search(search, "decoupled__degree", group="decoupled__n_branches", ax=ax_line)
ax_line.set_title("Error against degree")
labels = [f"r={r}, d={d}" for r in branches for d in degrees]
ax_time.barh(labels, fit_time.ravel(), color="C2")
ax_time.set_xlabel("fit time on the worker (s)")
ax_time.set_title("Fit time per candidate")
plt.tight_layout()

plt.show()
