"""Error measures and scorers over whole signals: scikit-learn's metrics by
name, the field's own (fit %, NRMSE, maximum error), in a cross-validation."""
import warnings

import numpy as np
import pytest
from sklearn.metrics import mean_squared_error, r2_score
from sklearn.model_selection import KFold, cross_val_score

from sklearn_pnlss import BLAEstimator
from sklearn_pnlss.metrics import (
    fit_percent, make_signal_scorer, max_error, nrmse, nrmse_by_band, rms_error, signal_scorer,
)
from sklearn_pnlss.signals import multisine

N = 128


def _linear_data():
    """Steady state of y(t) = 0.6 y(t-1) + 0.5 u(t-1) + 0.01 e(t)."""
    from scipy.signal import lfilter

    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), n_periods=2, n_realizations=6, random_state=0)
    rng = np.random.default_rng(0)
    y = np.stack([np.tile(lfilter([0.0, 0.5], [1, -0.6], np.tile(x[:N, 0], 4))[-N:], 2) for x in X])[..., None]
    return X, y + 0.01 * rng.standard_normal(y.shape)


def test_field_measures_by_hand():
    y = [np.array([[1.0, 2.0], [-1.0, 0.0]]), np.array([[1.0, 4.0], [-1.0, 2.0]])]
    y_hat = [np.array([[0.8, 2.0], [-1.0, 0.0]]), np.array([[1.0, 4.0], [-1.0, 3.0]])]
    # Output 0: error norm 0.2 over a spread norm 2 -> 0.1; output 1:
    # error 1 over the spread of (2, 0, 4, 2), norm sqrt(8) -> 0.3536.
    assert nrmse(y, y_hat) == pytest.approx((0.1 + 1 / np.sqrt(8)) / 2, rel=1e-12)
    assert fit_percent(y, y_hat) == pytest.approx(100 * (1 - (0.1 + 1 / np.sqrt(8)) / 2), rel=1e-12)
    assert max_error(y, y_hat) == 1.0
    assert rms_error(y, y_hat) == pytest.approx(np.sqrt((0.04 + 1.0) / 8), rel=1e-12)


def test_scorers_apply_any_metric_over_whole_signals():
    X, y = _linear_data()
    model = BLAEstimator(1, period=N).fit(X[:4], y[:4])
    pred = model.predict(X[4:])
    pooled_true, pooled_pred = np.concatenate(y[4:]), np.concatenate(pred)
    assert signal_scorer("r2")(model, X[4:], y[4:]) == pytest.approx(r2_score(pooled_true, pooled_pred), rel=1e-12)
    assert signal_scorer("neg_root_mean_squared_error")(model, X[4:], y[4:]) == pytest.approx(
        -np.sqrt(mean_squared_error(pooled_true, pooled_pred)), rel=1e-12)
    assert signal_scorer("neg_rms_db")(model, X[4:], y[4:]) == pytest.approx(model.score(X[4:], y[4:]), rel=1e-12)
    assert make_signal_scorer(nrmse, greater_is_better=False)(model, X[4:], y[4:]) == pytest.approx(
        -nrmse(y[4:], pred), rel=1e-12)
    # A first-order model of a first-order system: the fit is the noise's
    # (std 0.01), 100 (1 - 0.01 / std(y)), to within the noise's own spread.
    noise_limited = 100 * (1 - 0.01 / np.std(pooled_true))
    assert signal_scorer("fit_percent")(model, X[4:], y[4:]) == pytest.approx(noise_limited, abs=0.1)
    with pytest.raises(ValueError, match="Unknown signal scorer 'r3'; choose one of"):
        signal_scorer("r3")


def test_cross_validation_with_signal_scorers():
    """scikit-learn's string scorers give NaN on signals (its metrics refuse
    3-D arrays); signal_scorer gives the numbers."""
    X, y = _linear_data()
    cv = KFold(3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = cross_val_score(BLAEstimator(1, period=N), X, y, cv=cv, scoring="r2")
    assert np.all(np.isnan(plain))
    r2 = cross_val_score(BLAEstimator(1, period=N), X, y, cv=cv, scoring=signal_scorer("r2"))
    assert np.all((r2 > 0.999) & (r2 < 1.0))


def test_error_by_band_adds_up_and_finds_an_out_of_band_error():
    # Two zero-mean signals of unequal lengths: an in-band error (a gain)
    # and a resonance the input never excites, at 40 Hz.
    rng = np.random.default_rng(0)
    fs = 200.0
    y, y_hat = [], []
    for n in (1000, 600):  # whole periods of every sine: no leakage
        t = np.arange(n) / fs
        v = np.sin(2 * np.pi * np.arange(1, 26)[None, :, None] * t[:, None, None]
                   + rng.uniform(0, 2 * np.pi, (1, 25, 2))).sum(axis=1)
        y.append(v)
        y_hat.append(0.9 * v + 0.5 * np.sin(2 * np.pi * 40 * t)[:, None] * [1.0, 0.0])
    bands = nrmse_by_band(y, y_hat, fs, [0, 30, 50, 100.01])
    assert bands.shape == (3, 2)
    true = np.concatenate(y)
    err = true - np.concatenate(y_hat)
    total = np.sqrt((err**2).sum(axis=0) / (true**2).sum(axis=0))
    np.testing.assert_allclose(np.sqrt((bands**2).sum(axis=0)), total, rtol=1e-10)
    # The gain error lies in 0-30 Hz (0.1 of the output), the sine in
    # 30-50 Hz on output 0 only (rms 0.35 over the output's 3.5).
    np.testing.assert_allclose(bands[0], 0.1, rtol=1e-2)
    np.testing.assert_allclose(bands[1], [0.1, 0.0], atol=1e-9)
    with pytest.raises(ValueError, match="edges"):
        nrmse_by_band(y, y_hat, fs, [10, 5])
