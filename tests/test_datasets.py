import os
from pathlib import Path

import numpy as np
import pytest

from sklearn_pnlss.datasets import (
    load_bouc_wen_official,
    make_bouc_wen,
    simulate_bouc_wen,
)
from sklearn_pnlss.signals import bouc_wen_sweep

_OFFICIAL = ["uval_multisine.mat", "yval_multisine.mat", "uval_sinesweep.mat",
             "yval_sinesweep.mat", "train_multisine_official.mat"]


@pytest.fixture(scope="module")
def generated():
    return make_bouc_wen(random_state=0)


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def test_make_bouc_wen_layout(generated):
    d = generated
    assert d.X_train.shape == d.y_train.shape == (2, 2 * 8192, 1)
    assert d.X_test_multisine.shape == d.y_test_multisine.shape == (1, 8192, 1)
    assert d.X_test_sweep.shape == d.y_test_sweep.shape == (1, 153000, 1)
    assert [a.shape for a in d.X_test] == [(8192, 1), (153000, 1)]
    assert [a.shape for a in d.y_test] == [(8192, 1), (153000, 1)]
    np.testing.assert_array_equal(d.X_test[1][:, 0], d.X_test_sweep[0, :, 0])
    assert d.fs == 750.0 and d.period == 8192
    f = d.lines * 750.0 / 8192
    assert f.min() >= 5.0 and f.max() <= 150.0 and d.lines.size == 1584
    assert isinstance(d.DESCR, str) and "Bouc-Wen" in d.DESCR
    for X in (d.X_train[0, :, 0], d.X_train[1, :, 0], d.X_test_multisine[0, :, 0]):
        assert _rms(X) == pytest.approx(50.0, rel=1e-12)
    np.testing.assert_array_equal(d.X_train[:, :8192], d.X_train[:, 8192:])
    assert not np.allclose(d.X_train[0], d.X_train[1])
    assert not np.allclose(d.X_train[0, :8192], d.X_test_multisine[0])
    np.testing.assert_allclose(d.X_test_sweep[0, :, 0], bouc_wen_sweep())
    # outputs of the expected size (0.67 mm rms at 50 N)
    assert 6e-4 < _rms(d.y_test_multisine) < 7.5e-4


def test_make_bouc_wen_noise_and_steady_state(generated):
    d = generated
    for r in range(2):
        clean = simulate_bouc_wen(d.X_train[r, :8192, 0], periodic=True)
        noise = d.y_train[r, :, 0] - np.tile(clean, 2)
        assert _rms(noise) == pytest.approx(7.4e-6, rel=0.03)
        # independent over the whole record, not one period repeated
        assert abs(np.corrcoef(noise[:8192], noise[8192:])[0, 1]) < 0.05
    ms = simulate_bouc_wen(d.X_test_multisine[0, :, 0], periodic=True)
    np.testing.assert_allclose(d.y_test_multisine[0, :, 0], ms, rtol=0, atol=1e-15)


def test_make_bouc_wen_reproducible_and_noiseless_option(generated):
    d = make_bouc_wen(n_realizations=1, n_periods=1, noise_rms=0.0, random_state=0,
                      n_samples=1024, n_jobs=2)
    assert d.X_train.shape == (1, 1024, 1)
    again = make_bouc_wen(n_realizations=1, n_periods=1, noise_rms=0.0, random_state=0,
                          n_samples=1024)
    for key in ("X_train", "y_train", "X_test_multisine", "y_test_multisine"):
        np.testing.assert_array_equal(d[key], again[key])
    np.testing.assert_allclose(
        d.y_train[0, :, 0], simulate_bouc_wen(d.X_train[0, :, 0], periodic=True),
        rtol=0, atol=1e-15,
    )
    np.testing.assert_array_equal(d.y_test_sweep, generated.y_test_sweep)
    other = make_bouc_wen(n_realizations=1, n_periods=1, random_state=1, n_samples=1024)
    assert not np.allclose(other.X_train, d.X_train)


@pytest.mark.parametrize(
    "kwargs, match",
    [(dict(n_realizations=0), "n_realizations"), (dict(n_periods=1.5), "n_periods"),
     (dict(noise_rms=-1.0), "noise_rms"), (dict(rms=0.0), "rms")],
)
def test_make_bouc_wen_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        make_bouc_wen(**kwargs)


def test_simulate_bouc_wen_errors():
    with pytest.raises(ValueError, match="u must be 1-D"):
        simulate_bouc_wen(np.zeros((100, 1)), periodic=False)
    with pytest.raises(ValueError, match="NaN"):
        simulate_bouc_wen(np.full(100, np.nan), periodic=False)
    with pytest.raises(ValueError, match="decimation"):
        simulate_bouc_wen(np.zeros(100), periodic=False, decimation=(2, 5))


def test_generated_sweep_matches_official(generated, bouc_wen_dir):
    official = load_bouc_wen_official(bouc_wen_dir)
    y = official.y_test_sweep[0, :, 0]
    err = _rms(generated.y_test_sweep[0, :, 0] - y) / _rms(y)
    assert err < 1e-11, err  # measured 8.5e-13
    np.testing.assert_allclose(generated.X_test_sweep, official.X_test_sweep, atol=1e-8)


def test_load_bouc_wen_official(bouc_wen_dir):
    d = load_bouc_wen_official(str(bouc_wen_dir))
    assert d.X_train.shape == d.y_train.shape == (1, 32768, 1)
    assert d.X_train_raw.shape == d.y_train_raw.shape == (1, 40960, 1)
    np.testing.assert_array_equal(d.X_train[0], d.X_train_raw[0, 8192:])
    np.testing.assert_array_equal(d.y_train[0], d.y_train_raw[0, 8192:])
    assert d.X_test_multisine.shape == d.y_test_multisine.shape == (1, 8192, 1)
    assert d.X_test_sweep.shape == d.y_test_sweep.shape == (1, 153000, 1)
    assert [a.shape for a in d.y_test] == [(8192, 1), (153000, 1)]
    assert d.fs == 750.0 and d.period == 8192
    assert d.lines.size > 1500
    assert "32768" in d.DESCR


def test_load_bouc_wen_official_missing_file(bouc_wen_dir, tmp_path):
    for name in _OFFICIAL[:-1]:
        os.symlink(Path(bouc_wen_dir) / name, tmp_path / name)
    with pytest.raises(FileNotFoundError) as info:
        load_bouc_wen_official(tmp_path)
    assert "train_multisine_official.mat" in str(info.value)
    assert str(tmp_path) in str(info.value)


def test_load_bouc_wen_official_empty_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="uval_multisine.mat"):
        load_bouc_wen_official(tmp_path)
