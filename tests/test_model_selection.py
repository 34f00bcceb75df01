"""Selection on whole signals: held-out test signals, GridSearchCV with
joblib workers and on a Dask cluster."""
import numpy as np
import pytest
from joblib import parallel_backend
from sklearn.model_selection import GridSearchCV

from sklearn_pnlss import PNLSSRegressor
from sklearn_pnlss.metrics import rms_error
from sklearn_pnlss.model_selection import held_out_signals, mean_rms_db_scorer, worst_rms_db_scorer
from sklearn_pnlss.signals import multisine, swept_sine
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel

N = 256


def _truth():
    """Two states, an odd (cubic) nonlinearity: degree 3 is what it needs."""
    exE = monomial_exponents(3, (2, 3), active=[True, True, False])
    E = np.zeros((2, len(exE)))
    E[0, np.flatnonzero((exE == [3, 0, 0]).all(axis=1))] = -0.1
    return PNLSSModel(A=np.array([[0.8, 0.3], [-0.3, 0.6]]), B=np.array([[0.5], [0.2]]),
                      C=np.array([[1.0, 0.0]]), D=np.zeros((1, 1)), E=E, F=np.zeros((1, 0)),
                      exE=exE, exF=np.zeros((0, 3), dtype=np.int64))


def _train_test():
    truth = _truth()
    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=0.5, n_periods=2, n_realizations=3, random_state=0)
    y = np.stack([truth.simulate_signal(x, period=N) for x in X])
    X_ms, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=0.5, random_state=1)
    sweep = 0.7 * swept_sine(1500, fs=1.0, f_start=0.01, f_stop=0.3)[:, None]
    X_test = [X_ms[0], sweep]
    y_test = [truth.simulate_signal(X_ms[0], period=N), truth.simulate_signal(sweep)]
    return held_out_signals(X, y, X_test, y_test)


def _search(n_jobs):
    X, y, cv = _train_test()
    grid = {"degrees": [(2,), (2, 3)]}
    search = GridSearchCV(PNLSSRegressor(2, period=N, variables="states", max_iter=20), grid,
                          cv=cv, scoring=mean_rms_db_scorer, n_jobs=n_jobs, refit=False)
    return search.fit(X, y)


def test_grid_search_on_held_out_signals_picks_the_cubic_model():
    search = _search(n_jobs=2)
    assert search.best_params_ == {"degrees": (2, 3)}
    scores = search.cv_results_["mean_test_score"]
    assert scores.max() > scores.min() + 20  # the quadratic model cannot fit a cubic
    assert search.best_score_ > 60


def test_grid_search_on_a_dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster):
        with parallel_backend("dask"):
            search = _search(n_jobs=-1)
    reference = _search(n_jobs=1)
    assert search.best_params_ == reference.best_params_
    np.testing.assert_allclose(search.cv_results_["mean_test_score"],
                               reference.cv_results_["mean_test_score"], rtol=1e-10)


def test_refit_after_a_held_out_search_trains_on_the_training_signals_only():
    """GridSearchCV's default refit=True refits on every signal it was
    given; the held-out lists make that the training signals (the sweep,
    not whole periods, used to fail the refit after the whole search)."""
    from sklearn.base import clone
    from sklearn.pipeline import make_pipeline

    from sklearn_pnlss import BLAEstimator

    X, y, cv = _train_test()
    pipe = make_pipeline(BLAEstimator(2, period=N), PNLSSRegressor(2, variables="states", max_iter=20))
    search = GridSearchCV(pipe, {"pnlssregressor__degrees": [(2,), (2, 3)]}, cv=cv,
                          scoring=mean_rms_db_scorer).fit(X, y)
    assert search.best_params_ == {"pnlssregressor__degrees": (2, 3)}
    manual = clone(pipe).set_params(**search.best_params_).fit(X[:3], y[:3])
    X_test = X[3:]
    for a, b in zip(search.predict(X_test), manual.predict(X_test)):
        np.testing.assert_array_equal(a, b)
    # The refitted model scores on the test signals what the search measured.
    assert mean_rms_db_scorer(search.best_estimator_, X_test, y[3:]) == pytest.approx(search.best_score_, abs=1e-9)


def test_the_worst_signal_scorer_ranks_by_the_signal_a_model_misses_most():
    """A target on every test signal ("-100 dB on the multisine and on the
    sweep") ranks candidates by their worse signal, not their mean."""
    X, y, cv = _train_test()
    train, test = cv[0]
    model = PNLSSRegressor(2, period=N, variables="states", max_iter=20).fit(X[:3], y[:3])
    X_test, y_test = [X[i] for i in test], [y[i] for i in test]
    per_signal = [rms_error(t, p, db=True) for t, p in zip(y_test, model.predict(X_test))]
    assert worst_rms_db_scorer(model, X_test, y_test) == pytest.approx(-max(per_signal), abs=1e-12)
    assert mean_rms_db_scorer(model, X_test, y_test) == pytest.approx(-np.mean(per_signal), abs=1e-12)
    # The model is exact on the sweep but leaves its trusted range for a few
    # samples of the multisine: the mean of the two hides that miss.
    assert per_signal[1] < -200 and per_signal[0] > -60
    assert worst_rms_db_scorer(model, X_test, y_test) < mean_rms_db_scorer(model, X_test, y_test) - 50
