"""AveragedRegressor: one model fitted from several random starts, their
simulations averaged; the seeds, nested random states, layouts, the
hand-over from a BLA stage, and what the mean is worth on Bouc-Wen."""
import numpy as np
import pytest
from sklearn.base import clone
from sklearn.pipeline import make_pipeline

from sklearn_pnlss import AboveBandRegressor, AveragedRegressor, BLAEstimator, DecoupledPNLSSRegressor
from sklearn_pnlss.datasets import make_bouc_wen
from sklearn_pnlss.estimators.averaged import random_state_keys
from sklearn_pnlss.metrics import rms_error


@pytest.fixture(scope="module")
def bouc_wen():
    return make_bouc_wen(n_realizations=2, n_periods=1, random_state=0)


def _decoupled(max_iter=5, **settings):
    return DecoupledPNLSSRegressor(3, n_branches=2, degree=3, init="random", n_init=1, max_iter=max_iter,
                                   branch_basis="signed_powers", **settings)


def test_every_nested_random_state_is_seeded():
    wrapped = AboveBandRegressor(make_pipeline(BLAEstimator(3), _decoupled()), cutoff=0.2)
    assert random_state_keys(wrapped) == ["random_state", "regressor__decoupledpnlssregressor__random_state"]
    assert random_state_keys(BLAEstimator()) == []
    assert AveragedRegressor(random_state=7, n_estimators=3)._seeds().tolist() == [7, 8, 9]
    drawn = AveragedRegressor(random_state=np.random.RandomState(0), n_estimators=4)._seeds()
    assert len(set(drawn.tolist())) == 4
    np.testing.assert_array_equal(drawn, AveragedRegressor(random_state=np.random.RandomState(0), n_estimators=4)._seeds())


def test_the_mean_of_the_members_in_every_layout(bouc_wen):
    X, y = bouc_wen.X_train, bouc_wen.y_train
    pipeline = make_pipeline(BLAEstimator(3, period=8192), AveragedRegressor(_decoupled(), n_estimators=3,
                                                                            random_state=4))
    pipeline.fit(X, y)
    averaged = pipeline[-1]
    assert averaged.seeds_.tolist() == [4, 5, 6]
    assert [m.random_state for m in averaged.estimators_] == [4, 5, 6]
    assert averaged.n_features_in_ == 1 and averaged.n_outputs_ == 1
    assert averaged.n_params_ == sum(m.n_params_ for m in averaged.estimators_) > 0
    X_new = bouc_wen.X_test_multisine
    members = [m.predict(pipeline[0].transform(X_new)) for m in averaged.estimators_]
    assert not np.allclose(members[0], members[1])  # other starts, other models
    np.testing.assert_allclose(pipeline.predict(X_new), np.mean(members, axis=0), rtol=1e-12, atol=0)
    as_list = pipeline.predict([X_new[0], X_new[0, :4096]])
    assert isinstance(as_list, list) and as_list[1].shape == (4096, 1)
    np.testing.assert_allclose(as_list[0], np.mean(members, axis=0)[0], rtol=1e-12, atol=0)
    # a record cut from a longer run: every member starts from the state the measured window shows it
    cut, window = bouc_wen.X_test_sweep[:, 5000:9000], bouc_wen.y_test_sweep[:, 5000:5100]
    started = [m.predict(cut, y_init=window) for m in averaged.estimators_]
    np.testing.assert_allclose(averaged.predict(cut, y_init=window), np.mean(started, axis=0), rtol=1e-12, atol=0)
    assert not np.allclose(averaged.predict(cut), averaged.predict(cut, y_init=window))


def test_the_first_member_is_the_plain_fit(bouc_wen):
    """An int random_state s: the first member is what the regressor with
    random_state=s fits, so the mean adds to a fit one already has."""
    X, y = BLAEstimator(3, period=8192).fit(bouc_wen.X_train, bouc_wen.y_train).transform(bouc_wen.X_train), \
        bouc_wen.y_train
    averaged = AveragedRegressor(_decoupled(), n_estimators=2, random_state=11).fit(X, y)
    plain = clone(_decoupled(random_state=11)).fit(X, y)
    np.testing.assert_array_equal(averaged.estimators_[0].predict(X), plain.predict(X))


def test_a_regressor_without_randomness_is_refused(bouc_wen):
    with pytest.raises(ValueError, match="regressor: BLAEstimator has no random_state"):
        AveragedRegressor(BLAEstimator(2)).fit(bouc_wen.X_train, bouc_wen.y_train)
    with pytest.raises(ValueError, match="requires y"):
        AveragedRegressor(_decoupled()).fit(bouc_wen.X_train, None)


def test_a_start_gone_astray_costs_the_mean_little(bouc_wen):
    """Four starts of a small decoupled model on Bouc-Wen (30 iterations):
    three land at -92.2 dB on the test multisine, one at -87.0 dB. Their
    mean keeps the good starts' figure, and on the sweep, a waveform the
    fit never saw, it beats every member: -99.5 dB against -99.2 dB for
    the best start alone (measured)."""
    start = BLAEstimator(3, period=8192).fit(bouc_wen.X_train, bouc_wen.y_train)
    with pytest.warns(UserWarning):  # the start gone astray is unstable at rest
        averaged = AveragedRegressor(_decoupled(max_iter=30), n_estimators=4, random_state=0).fit(
            start.transform(bouc_wen.X_train), bouc_wen.y_train)
    for X, Y in ((bouc_wen.X_test_multisine, bouc_wen.y_test_multisine), (bouc_wen.X_test_sweep, bouc_wen.y_test_sweep)):
        members = sorted(rms_error(Y, m.predict(X), db=True) for m in averaged.estimators_)
        mean = rms_error(Y, averaged.predict(X), db=True)
        assert members[-1] > members[0] + 4  # one start went astray by more than 4 dB
        assert mean < members[1] + 0.05  # the mean is as good as the good starts, or better
