"""Signal convention: layouts, errors naming the argument and the fix."""
import numpy as np
import pytest

from sklearn_pnlss.metrics import rms_error
from sklearn_pnlss.utils.validation import (
    as_signal_list,
    check_period,
    is_periodic,
    restore_layout,
)


def test_layouts_round_trip():
    X3 = np.zeros((2, 10, 1))
    sig, lay = as_signal_list(X3)
    assert len(sig) == 2 and sig[0].shape == (10, 1) and lay.kind == "3d"
    assert restore_layout(sig, lay).shape == (2, 10, 1)
    sig, lay = as_signal_list([np.zeros(5), np.zeros(7)])
    assert [s.shape for s in sig] == [(5, 1), (7, 1)] and lay.kind == "list"
    sig, lay = as_signal_list(np.zeros(6))
    assert sig[0].shape == (6, 1) and restore_layout(sig, lay, squeeze_1d=True).shape == (6,)
    sig, lay = as_signal_list(np.zeros((6, 2)))
    assert len(sig) == 1 and sig[0].shape == (6, 2)
    # Nested plain lists are an array (sklearn's X.tolist()), not signals.
    sig, lay = as_signal_list(np.zeros((6, 2)).tolist())
    assert len(sig) == 1 and sig[0].shape == (6, 2)


@pytest.mark.parametrize(
    "X, match",
    [
        (np.array([0.0, np.nan, 1.0]), "NaN or infinity"),
        (np.array([[0.0], [np.inf]]), "NaN or infinity"),
        (np.zeros((1, 1)), "n_samples = 1"),
        ([], "empty list"),
        ([np.zeros((5, 1)), np.zeros((5, 2))], "same number of channels"),
        (np.zeros((2, 2, 2, 2)), "4 dimensions"),
        # (n_signals, n_samples) without the channel axis: say so.
        (np.zeros((2, 300)), r"X\[\.\.\., None\] \(shape \(2, 300, 1\)\)"),
    ],
)
def test_bad_signals_raise_clear_errors(X, match):
    with pytest.raises(ValueError, match=match):
        as_signal_list(X)


def test_period_checks():
    assert check_period(None) is None and check_period(np.int64(8)) == 8
    with pytest.raises(ValueError, match="period must be at least 2"):
        check_period(0)
    with pytest.raises(TypeError, match="period must be a positive integer"):
        check_period(2.5)
    assert is_periodic(16, 8) and not is_periodic(12, 8) and not is_periodic(4, 8)


def test_rms_error_in_metres_and_db():
    y = [np.zeros(3), np.zeros(1)]
    yp = [np.full(3, 2e-5), np.full(1, 2e-5)]
    assert rms_error(y, yp) == pytest.approx(2e-5)
    assert rms_error(y, yp, db=True) == pytest.approx(20 * np.log10(2e-5))
    with pytest.raises(ValueError, match="same number of signals"):
        rms_error(y, yp[:1])


def test_transposed_signals_are_named_in_every_estimator():
    """The commonest mistake, (n_signals, n_samples) without the channel
    axis, gets the same hint from the estimators and the gap diagnosis."""
    from sklearn_pnlss import BLAEstimator, PNLSSRegressor
    from sklearn_pnlss.gap import GapDiagnosis
    from sklearn_pnlss.physics import Oscillator

    X = np.random.default_rng(0).standard_normal((2, 512))
    for est in (BLAEstimator(2, period=256), PNLSSRegressor(2, period=256)):
        with pytest.raises(ValueError, match=r"add the channel axis: X\[\.\.\., None\]"):
            est.fit(X, X)
    with pytest.raises(ValueError, match=r"\[\.\.\., None\]"):
        GapDiagnosis(nominal=Oscillator(mass=2.0, damping=10.0, stiffness=5e4), fs=750.0).fit(X, X)
