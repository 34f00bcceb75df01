"""Fitted models as objects: readable repr, summary numbers equal to the
model's own, and the export of the linear part to scipy.signal."""
import json

import numpy as np
import pytest
from scipy import signal

from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor
from sklearn_pnlss.metrics import rms_error
from sklearn_pnlss.statespace.linear import frequency_response

SMALL_FS, SMALL_PERIOD = 100.0, 256  # of the small_data fixture (conftest.py)


def test_repr_shows_the_non_default_parameters():
    assert repr(PNLSSRegressor(3, degrees=(2, 3), variables="states", period=8192)) == (
        "PNLSSRegressor(period=8192, variables='states')"
    )
    assert repr(BLAEstimator()) == "BLAEstimator()"
    assert "n_branches=2" in repr(DecoupledPNLSSRegressor(n_branches=2))


def test_bla_summary_numbers_are_the_models(small_pipeline):
    bla = small_pipeline[0]
    s = bla.summary()
    assert s.n_params == bla.n_params_ == 9  # n = 2, m = p = 1: 4 + 2 + 2 + 1
    assert (s.n_linear_params, s.n_nonlinear_params) == (9, 0)
    assert (s.n_states, s.n_inputs, s.n_outputs) == (2, 1, 1)
    assert s.fs == SMALL_FS
    np.testing.assert_allclose(s.natural_frequencies, bla.natural_frequencies_)
    np.testing.assert_allclose(s.damping_ratios, bla.damping_ratios_)
    # One pole per mode; each a true eigenvalue of A_, matching its frequency.
    eig = np.linalg.eigvals(bla.A_)
    for z, f in zip(s.poles, s.natural_frequencies):
        assert np.min(np.abs(eig - z)) < 1e-12
        assert abs(abs(SMALL_FS * np.log(z)) / (2 * np.pi) - f) < 1e-9
    assert s.structure["excited_lines"] == bla.lines_.size
    text = str(s)
    assert "parameters: 9 (9 linear, 0 nonlinear)" in text
    assert f"{s.natural_frequencies[-1]:9.4g} Hz" in text


def test_pnlss_summary_counts_fit_figures_and_scores(small_pipeline, small_data):
    X_val, y_val = small_data.X_val, small_data.y_val
    pnlss = small_pipeline[1]
    s = pnlss.summary(X_val, y_val)
    assert s.n_params == pnlss.n_params_ == s.n_linear_params + s.n_nonlinear_params
    assert s.n_nonlinear_params == pnlss.n_nonlinear_params_ == pnlss.E_.size
    assert s.structure["degrees"] == (2, 3)
    assert s.structure["monomials"]["state_equation"] == pnlss.exponents_E_.shape[0]
    assert s.fit["iterations"] == pnlss.n_iter_ and s.fit["kept_iteration"] == pnlss.best_iteration_
    assert s.fit["cost_change_db"] == pytest.approx(10 * np.log10(pnlss.cost_history_[-1] / pnlss.cost_history_[0]))
    assert s.fit["cost_change_db"] < 0
    # The BLA stage carried fs through the Pipeline.
    assert s.fs == SMALL_FS
    assert s.scores["db"] == pytest.approx(rms_error(y_val, pnlss.predict(X_val), db=True))
    assert s.scores["rms"] == pytest.approx(rms_error(y_val, pnlss.predict(X_val)))
    with pytest.raises(ValueError, match="both X and y"):
        pnlss.summary(X_val)


def test_decoupled_summary_reports_branches_and_starts(small_pipeline):
    dec = small_pipeline[-1]
    s = dec.summary()
    n, m, r, d = 2, 1, 1, 3
    assert s.n_nonlinear_params == dec.n_nonlinear_params_ == (2 * n + m + d) * r
    assert s.n_params == dec.n_params_ == s.n_linear_params + s.n_nonlinear_params
    assert (s.structure["branches"], s.structure["degree"]) == (r, d)
    assert s.fit["starts"] == 2 and s.fit["kept_start"] == dec.best_init_
    assert s.fit["start_scores_db"] == list(dec.init_scores_)
    # Validation signals were given: the kept iterate's validation error.
    assert s.fit["validation_error_db"] == dec.validation_history_[dec.best_iteration_]
    assert s.fit["validation_error_db"] == pytest.approx(dec.init_scores_.min())
    # JSON-ready, and the poles survive the trip.
    d = json.loads(json.dumps(s.to_dict()))
    np.testing.assert_allclose([complex(*z) for z in d["poles"]], s.poles)
    assert d["n_params"] == dec.n_params_


def test_summary_frequencies_follow_fs(small_pipeline):
    bla = small_pipeline[0]
    in_hz = bla.summary().natural_frequencies
    per_sample = bla.summary(fs=1.0).natural_frequencies
    np.testing.assert_allclose(in_hz, per_sample * SMALL_FS)


@pytest.mark.parametrize("stage", [0, 1, 2])
def test_to_statespace_is_the_linear_part(small_pipeline, stage):
    est = small_pipeline[stage]
    sys = est.to_statespace()
    assert isinstance(sys, signal.StateSpace)
    assert sys.dt == pytest.approx(1 / SMALL_FS)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(sys, name), getattr(est, f"{name}_"))
    # Its frequency response is the model's linear part's.
    w = 2 * np.pi * np.arange(1, 40) / SMALL_PERIOD
    _, H = signal.dfreqresp(sys, w=w)
    G = frequency_response(est.A_, est.B_, est.C_, est.D_, np.exp(1j * w))[:, 0, 0]
    np.testing.assert_allclose(np.ravel(H), G, rtol=1e-9)
    assert est.to_statespace(fs=10.0).dt == pytest.approx(0.1)


def test_to_statespace_of_the_bla_reproduces_its_fitted_frf(small_pipeline):
    bla = small_pipeline[0]
    w = 2 * np.pi * bla.lines_ / SMALL_PERIOD
    _, H = signal.dfreqresp(bla.to_statespace(), w=w)
    np.testing.assert_allclose(np.ravel(H), bla.frf_model_[:, 0, 0], rtol=1e-9)


def test_to_statespace_without_fs_is_discrete_with_unspecified_step(small_data):
    bla = BLAEstimator(2, period=SMALL_PERIOD).fit(small_data.X, small_data.y)
    assert bla.to_statespace().dt is True
    assert bla.summary().fs is None
    assert "cycles/sample" in str(bla.summary())
