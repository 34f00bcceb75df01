"""What the benchmark scripts share: paths, the machine description,
timing, the cold/warm numba compile measurement and the results file."""
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_DATA = Path(os.environ.get("SKLEARN_PNLSS_DATA", REPO.parent / "shared" / "data" / "bouc_wen"))


def header():
    """Date, machine and library versions for a results file."""
    import numba
    import scipy
    import sklearn

    import sklearn_pnlss

    return {
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "environment": {
            "python": platform.python_version(),
            "platform": platform.platform(),
            "cpu_count": os.cpu_count(),
            "numpy": np.__version__,
            "numba": numba.__version__,
            "scipy": scipy.__version__,
            "scikit-learn": sklearn.__version__,
            "sklearn_pnlss": sklearn_pnlss.__version__,
        },
    }


def timeit(func, repeat):
    """Median and minimum wall time of ``repeat`` calls, and the last result."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = func()
        times.append(time.perf_counter() - t0)
    return {"median_s": statistics.median(times), "min_s": min(times), "n": repeat}, result


def first_call(code, cache_dir=None):
    """Run ``code`` in a fresh interpreter; it prints a JSON object with
    ``import``, ``first_call`` and ``second_call`` times. Their difference is
    the numba compilation (cold cache) or cache load (warm cache)."""
    env = dict(os.environ)
    if cache_dir is not None:
        # A user-provided cache folder takes precedence over the in-tree
        # __pycache__, so an empty one forces a full compilation without
        # touching the cache the library normally uses.
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True)
    times = json.loads(out.stdout.strip().splitlines()[-1])
    times["compile_or_load"] = times["first_call"] - times["second_call"]
    return times


def score_test_signals(model, data):
    """{"multisine": dB, "sweep": dB} of ``model`` on the test signals of
    ``data`` (``X_test_multisine``, ...), None where the simulation diverges."""
    from sklearn_pnlss import DivergenceError

    out = {}
    for key in ("multisine", "sweep"):
        try:
            out[key] = -float(model.score(data[f"X_test_{key}"], data[f"y_test_{key}"]))
        except DivergenceError:
            out[key] = None
    return out


def _plain(value):
    """numpy scalars and arrays as JSON numbers and lists; anything else
    (a place's tuple is already a list) as its text."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def write_results(results, output):
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(results, indent=2, default=_plain) + "\n")
    print(f"written {output}")
