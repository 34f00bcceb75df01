"""Shared fixtures: where the official Bouc-Wen files live (when present), and
a small fitted BLA -> PNLSS -> decoupled pipeline for the tests of figures,
summaries and saving."""
import os
from pathlib import Path

import numpy as np
import pytest

_DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "bouc_wen"


def official_data_dir():
    """Folder with the official benchmark files, or None when absent.

    ``SKLEARN_PNLSS_DATA`` overrides the default ``../shared/data/bouc_wen``.
    """
    path = Path(os.environ.get("SKLEARN_PNLSS_DATA", _DEFAULT_DATA))
    return path if (path / "uval_multisine.mat").exists() else None


@pytest.fixture(scope="session")
def bouc_wen_dir():
    path = official_data_dir()
    if path is None:
        pytest.skip("official Bouc-Wen files not found (../shared/data/bouc_wen)")
    return path


def _f16_folder():
    """Folder with the F-16 benchmark's files (``SKLEARN_PNLSS_F16_DATA``,
    else ``../shared/data/f16``), or None when absent."""
    path = Path(os.environ.get("SKLEARN_PNLSS_F16_DATA", _DEFAULT_DATA.parent / "f16"))
    for folder in (path, path / "BenchmarkData", path / "F16GVT_Files" / "BenchmarkData"):
        if (folder / "F16Data_FullMSine_Level3.mat").exists():
            return folder
    return None


@pytest.fixture(scope="session")
def f16_dir():
    path = _f16_folder()
    if path is None:
        pytest.skip("F-16 benchmark files not found (../shared/data/f16, or set SKLEARN_PNLSS_F16_DATA)")
    return path


@pytest.fixture(autouse=True)
def _seeded_global_rng():
    """Estimators left at ``random_state=None`` draw from numpy's global
    generator (a fit's check on new realisations of its inputs does): seeded
    for every test, a test's outcome does not hang on the tests before it."""
    np.random.seed(0)


SMALL_PERIOD = 256
SMALL_FS = 100.0


def _small_signals(n_realizations, seed):
    """Steady-state multisines through a small exactly decoupled system: two
    states, one cubic branch of a mix of both states and the input."""
    import numpy as np

    from sklearn_pnlss.signals import multisine
    from sklearn_pnlss.statespace.decoupled import DecoupledModel

    truth = DecoupledModel(
        A=np.array([[0.8, 0.3], [-0.3, 0.6]]), B=np.array([[0.5], [0.2]]),
        C=np.array([[1.0, 0.0]]), D=np.zeros((1, 1)),
        Wx=np.array([[1.0], [0.3]]), Wy=np.zeros((1, 1)),
        V=np.array([[0.8], [0.5], [0.3]]), G=np.array([[0.0, 0.05, -0.2]]),
    )
    X, _ = multisine(SMALL_PERIOD, fs=SMALL_FS, f_band=(1.0, 45.0), rms=0.5, n_periods=2,
                     n_realizations=n_realizations, random_state=seed)
    return X, np.stack([truth.simulate_signal(x, period=SMALL_PERIOD) for x in X])


@pytest.fixture(scope="session")
def small_data():
    """Training signals ``X, y`` (3 realisations of 2 periods) and validation
    signals ``X_val, y_val`` (1 realisation) of the small system, with their
    ``period`` and sampling frequency ``fs``."""
    from types import SimpleNamespace

    X, y = _small_signals(3, seed=0)
    X_val, y_val = _small_signals(1, seed=5)
    return SimpleNamespace(X=X, y=y, X_val=X_val, y_val=y_val, period=SMALL_PERIOD, fs=SMALL_FS)


@pytest.fixture(scope="session")
def small_pipeline(small_data):
    """A fitted BLA -> PNLSS -> decoupled Pipeline on the small system (a
    second or two). Tests read it and must not refit or modify it."""
    from sklearn.pipeline import make_pipeline

    from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor

    X, y, X_val, y_val = small_data.X, small_data.y, small_data.X_val, small_data.y_val
    pipe = make_pipeline(
        BLAEstimator(2, period=SMALL_PERIOD, fs=SMALL_FS),
        PNLSSRegressor(2, degrees=(2, 3), period=SMALL_PERIOD, max_iter=20),
        DecoupledPNLSSRegressor(2, n_branches=1, degree=3, period=SMALL_PERIOD, n_init=2, max_iter=20,
                                random_state=0),
    )
    return pipe.fit(X, y, decoupledpnlssregressor__X_val=X_val, decoupledpnlssregressor__y_val=y_val)
