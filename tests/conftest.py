"""Shared fixtures: where the official Bouc-Wen files live (when present)."""
import os
from pathlib import Path

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
