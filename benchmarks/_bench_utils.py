"""What the benchmark scripts share: paths, the machine description,
timing, the cold/warm numba compile measurement and the results file."""
import ast
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


def setting_value(text):
    """A ``KEY=VALUE`` option's value: a Python literal (3, 0.5, True),
    else the text."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def commit_of(checkout=REPO):
    """The short hash of ``checkout``'s HEAD."""
    return subprocess.run(["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()


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


def paper_training_draw(seed):
    """The seed paper's training data of one draw: two realisations of two
    periods at 55 N rms for training and the steady-state period of a third
    for validation; returns (data, X, y, X_val, y_val)."""
    from sklearn_pnlss.datasets import make_bouc_wen

    data = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, noise_rms=8e-6, random_state=seed)
    P = data.period
    return data, data.X_train[:2], data.y_train[:2], data.X_train[2:, P:], data.y_train[2:, P:]


def paper_start(init, data, X, y):
    """The fitted model a decoupled one of the seed paper's setting starts
    from: the BLA (``init="random"``) or the full model in the states and
    input, degrees 2 and 3, 200 iterations (``init="cpd"``)."""
    from sklearn_pnlss import BLAEstimator, PNLSSRegressor

    if init == "cpd":
        return PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=data.period, max_iter=200).fit(X, y)
    return BLAEstimator(3, period=data.period, fs=data.fs).fit(X, y)


def official_test_signals(data_dir):
    """{"multisine": (X, y), "sweep": (X, y)}: the official Bouc-Wen test signals."""
    from sklearn_pnlss.datasets import load_bouc_wen_official

    official = load_bouc_wen_official(data_dir)
    return {"multisine": (official.X_test_multisine, official.y_test_multisine),
            "sweep": (official.X_test_sweep, official.y_test_sweep)}


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
