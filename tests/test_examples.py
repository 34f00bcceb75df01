"""Every gallery example runs as a plain script, headless, in a clean folder.

The examples are documentation users copy from; a broken one is a bug. Each
runs in its own interpreter (as sphinx-gallery and users would run it), with
the Agg backend so no window opens, and in a temporary working directory so
that any file it writes lands there and not in the source tree.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES_DIR = Path(__file__).resolve().parents[1] / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("plot_*.py"))
# Each example is meant to run in well under 20 s; the margin covers a cold
# numba cache (first compilation of the simulator) on a slow machine.
TIMEOUT = 300


def test_examples_are_found():
    assert EXAMPLES, f"no plot_*.py example found in {EXAMPLES_DIR}"


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    result = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert result.returncode == 0, (
        f"{script.name} exited with code {result.returncode}\n"
        f"--- stdout ---\n{result.stdout[-3000:]}\n--- stderr ---\n{result.stderr[-3000:]}"
    )
