"""Pipeline hand-over: each stage starts from the fitted stage before it,
and Pipeline(memory=...) caches the earlier stages across a grid search."""
import pickle

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.model_selection import GridSearchCV
from sklearn.pipeline import Pipeline, make_pipeline

from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.metrics import rms_db_scorer
from sklearn_pnlss.signals import multisine
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel
from sklearn_pnlss.utils.handover import attach_stage, detach_stage

N = 256


def _data(n_realizations=4, seed=0):
    """Steady-state data of a 2-state system with a hardening cubic."""
    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=0.5, n_periods=2,
                     n_realizations=n_realizations, random_state=seed)
    exE = monomial_exponents(3, (3,), active=[True, True, False])
    E = np.zeros((2, len(exE)))
    E[0, 0] = -0.1  # x1 ** 3
    truth = PNLSSModel(A=np.array([[0.8, 0.3], [-0.3, 0.6]]), B=np.array([[0.5], [0.2]]),
                       C=np.array([[1.0, 0.0]]), D=np.zeros((1, 1)), E=E, F=np.zeros((1, 0)),
                       exE=exE, exF=np.zeros((0, 3), dtype=np.int64))
    return X, np.stack([truth.simulate_signal(x, period=N) for x in X])


class CountingBLA(BLAEstimator):
    fits = 0

    def fit(self, X, y):
        type(self).fits += 1
        return super().fit(X, y)


def test_stage_signals_survive_slicing_and_pickling():
    X = np.arange(12.0).reshape(2, 6, 1)
    stage = BLAEstimator(2)
    Xs = attach_stage(X, stage)
    assert Xs[1:].stage is stage
    back = pickle.loads(pickle.dumps(Xs))
    assert isinstance(back.stage, BLAEstimator) and np.array_equal(back, X)
    plain, got = detach_stage(back)
    assert type(plain) is np.ndarray and got.get_params() == stage.get_params()
    lst = attach_stage([X[0], X[1, :4]], stage)
    assert pickle.loads(pickle.dumps(lst)).stage.get_params() == stage.get_params()


def test_pnlss_starts_from_the_bla_stage():
    X, y = _data()
    pipe = make_pipeline(BLAEstimator(2, period=N), PNLSSRegressor(2, period=N, max_iter=10))
    pipe.fit(X, y)
    bla, pnlss = pipe[0], pipe[-1]
    assert pnlss.linear_model_ is bla
    alone = PNLSSRegressor(2, period=N, max_iter=10).fit(X, y)
    np.testing.assert_allclose(pipe.predict(X), alone.predict(X), rtol=1e-8, atol=1e-12)
    # The nonlinear stage is far better than the linear one on this system.
    assert pipe.score(X, y) > bla.score(X, y) + 20
    # clone and pickle keep working on the fitted pipeline.
    assert clone(pipe)[-1].get_params() == pnlss.get_params()
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(pipe)).predict(X), pipe.predict(X))


def test_wrong_stage_order_is_a_clear_error():
    X, y = _data()
    with pytest.raises(TypeError, match="starts from a BLAEstimator"):
        make_pipeline(PNLSSRegressor(2, period=N, max_iter=1), PNLSSRegressor(2, period=N, max_iter=1)).fit(X, y)
    with pytest.raises(ValueError, match="n_states"):
        make_pipeline(BLAEstimator(3, period=N), PNLSSRegressor(2, period=N, max_iter=1)).fit(X, y)


def test_memory_caches_the_earlier_stages_in_a_grid_search(tmp_path):
    X, y = _data(n_realizations=4)
    CountingBLA.fits = 0
    pipe = Pipeline([("bla", CountingBLA(2, period=N)), ("pnlss", PNLSSRegressor(2, period=N))],
                    memory=str(tmp_path))
    search = GridSearchCV(pipe, {"pnlss__max_iter": [1, 3, 5]}, cv=2, scoring=rms_db_scorer)
    search.fit(X, y)
    # Two splits plus the final refit: the BLA is fitted once per distinct
    # training set, not once per grid point.
    assert CountingBLA.fits == 3
    assert search.best_params_ == {"pnlss__max_iter": 5}


def test_set_output_says_why_pandas_is_not_available():
    from sklearn.pipeline import make_pipeline

    from sklearn_pnlss import BLAEstimator, PNLSSRegressor

    pipe = make_pipeline(BLAEstimator(2), PNLSSRegressor(2))
    assert pipe.set_output(transform="default") is pipe
    with pytest.raises(ValueError, match="no pandas form"):
        pipe.set_output(transform="pandas")


def test_period_is_handed_down_the_pipeline(small_data):
    """A PNLSS stage without period after a BLA stage with one fits and
    predicts periodic signals in steady state, as with the period given
    (it used to treat them as transients, 3.6 dB worse on Bouc-Wen)."""
    from conftest import SMALL_PERIOD

    X, y, X_val, y_val = small_data.X, small_data.y, small_data.X_val, small_data.y_val
    handed = make_pipeline(BLAEstimator(2, period=SMALL_PERIOD), PNLSSRegressor(2, max_iter=10)).fit(X, y)
    given = make_pipeline(BLAEstimator(2, period=SMALL_PERIOD),
                          PNLSSRegressor(2, period=SMALL_PERIOD, max_iter=10)).fit(X, y)
    assert handed[-1].period_ == SMALL_PERIOD and handed[-1].period is None
    assert handed.score(X_val, y_val) == given.score(X_val, y_val)
    with pytest.raises(ValueError, match="give both the same period"):
        make_pipeline(BLAEstimator(2, period=SMALL_PERIOD), PNLSSRegressor(2, period=2 * SMALL_PERIOD)).fit(X, y)
