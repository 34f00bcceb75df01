"""The field's measured benchmarks (nonlinearbenchmark.org) by their official
splits, read from files on disk, and the conversion of the official loader's
data objects.

The community's loader, the ``nonlinear-benchmarks`` package, downloads the
files and fixes the train/test split of each benchmark and the length of the
state-initialisation window that the test score skips. The same splits and
windows are written here, so that a folder of the files (what machines
without that download have) gives the same data; :func:`from_io_data`
turns the loader's ``Input_output_data`` objects into the library's signal
layout for users who already have them.
"""
import os
from pathlib import Path

import numpy as np
from sklearn.utils import Bunch

__all__ = ["BENCHMARKS", "from_io_data", "load_benchmark"]

ENV_VAR = "SKLEARN_PNLSS_BENCHMARK_DATA"


def _csv(path):
    """Columns of a CSV file with a header row, by name (empty cells NaN)."""
    table = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
    return {name: table[name] for name in table.dtype.names}


def _until_nan(values):
    """A column up to its first empty cell (shorter columns of one file)."""
    bad = np.flatnonzero(~np.isfinite(values))
    return values[: bad[0]] if bad.size else values


def _wh2009(folder):
    data = _csv(folder / "WienerHammerBenchmark.csv")
    u, y = _until_nan(data["uBenchMark"]), _until_nan(data["yBenchMark"])
    fs = float(data["fs"][0])
    # The official split: samples 5,200-183,999 hold the excitation; the
    # first 100,000 of them estimate, the rest test.
    u, y = u[5200:184000], y[5200:184000]
    return (u[:100000], y[:100000]), (u[100000:], y[100000:]), 1.0 / fs


def _cascaded_tanks(folder):
    data = _csv(folder / "dataBenchmark.csv")
    est = (_until_nan(data["uEst"]), _until_nan(data["yEst"]))
    val = (_until_nan(data["uVal"]), _until_nan(data["yVal"]))
    return est, val, float(data["Ts"][0])


def _emps(folder):
    from scipy.io import loadmat

    records = []
    for name in ("DATA_EMPS.mat", "DATA_EMPS_PULSES.mat"):
        content = loadmat(folder / name)
        # Input: the motor force on the load side (vir, N); output: the
        # measured position (qm, m). The drive runs in closed loop on qg.
        records.append((content["vir"][:, 0], content["qm"][:, 0], float(content["t"][1, 0] - content["t"][0, 0])))
    (u_e, y_e, ts), (u_t, y_t, _) = records
    return (u_e, y_e), (u_t, y_t), ts


# name -> (folder, reader, samples skipped by the test score, unit of the
# output, factor from the output's unit to the unit the field reports in,
# that unit, description)
BENCHMARKS = {
    "wh2009": ("wh2009", _wh2009, 50, "V", 1e3, "mV",
               "Wiener-Hammerstein benchmark 2009 (Schoukens, Suykens, Ljung): an electronic circuit, "
               "a static nonlinearity between two linear filters, 51.2 kHz."),
    "cascaded_tanks": ("cascaded_tanks", _cascaded_tanks, 50, "V", 1.0, "V",
                       "Cascaded tanks (Schoukens, Mattsson, Wigren, Noel 2016): water levels of two "
                       "tanks fed by a pump, with overflow, sampled every 4 s."),
    "emps": ("emps", _emps, 20, "m", 1e3, "mm",
             "Electro-mechanical positioning system (Janot, Gautier, Brunot 2019): a prismatic "
             "drive with friction, measured in closed loop; input the motor force, output the position."),
}


def load_benchmark(name, path=None):
    """Load one of the field's measured benchmarks by its official split.

    The splits and state-initialisation windows are those of the official
    loader (the ``nonlinear-benchmarks`` package); the files are read from a
    folder instead of being downloaded.

    Parameters
    ----------
    name : {"wh2009", "cascaded_tanks", "emps"}
        ``"wh2009"``: ``WienerHammerBenchmark.csv``; ``"cascaded_tanks"``:
        ``dataBenchmark.csv``; ``"emps"``: ``DATA_EMPS.mat`` (estimation) and
        ``DATA_EMPS_PULSES.mat`` (test). For the F-16 use
        :func:`~sklearn_pnlss.datasets.load_f16`.
    path : str, path-like or None, default=None
        The folder holding the benchmark's files, or a folder holding one
        subfolder per benchmark (named as ``name``). None reads it from the
        environment variable ``SKLEARN_PNLSS_BENCHMARK_DATA``.

    Returns
    -------
    data : :class:`~sklearn.utils.Bunch`
        ``X_train, y_train``: the estimation record, arrays of shape (1,
        n_samples, 1); ``X_test, y_test``: the test record; ``skip``: the
        samples at the start of the test record that the official score
        leaves out (the state-initialisation window; pass it to the metrics
        of :mod:`sklearn_pnlss.metrics`); ``sampling_time`` (s);
        ``unit`` of the output; ``report_unit`` and ``report_scale``: the
        unit the field reports errors in and the factor from ``unit`` to
        it; ``name``, ``DESCR``.

    Raises
    ------
    FileNotFoundError
        If no folder is given or the benchmark's files are not in it.

    Examples
    --------
    >>> from sklearn_pnlss.datasets import load_benchmark
    >>> data = load_benchmark("wh2009", "path/to/data")  # doctest: +SKIP
    >>> data.X_train.shape, data.X_test.shape, data.skip  # doctest: +SKIP
    ((1, 100000, 1), (1, 78800, 1), 50)
    """
    if name not in BENCHMARKS:
        raise ValueError(f"name must be one of {sorted(BENCHMARKS)}; got {name!r}.")
    sub, reader, skip, unit, scale, report_unit, descr = BENCHMARKS[name]
    if path is None:
        path = os.environ.get(ENV_VAR)
        if not path:
            raise FileNotFoundError(
                f"No folder for the {name} benchmark: pass path= (the folder of its files) or set "
                f"{ENV_VAR} to a folder with one subfolder per benchmark."
            )
    folder = Path(path).expanduser()
    if (folder / sub).is_dir():
        folder = folder / sub
    try:
        (u_tr, y_tr), (u_te, y_te), ts = reader(folder)
    except (FileNotFoundError, OSError) as missing:
        raise FileNotFoundError(
            f"The {name} benchmark's files are not in {str(folder)!r} ({missing}). Pass path= the folder "
            f"holding them, or set {ENV_VAR}."
        ) from None
    signal = lambda v: np.asarray(v, dtype=np.float64).reshape(1, -1, 1)  # noqa: E731
    return Bunch(
        X_train=signal(u_tr), y_train=signal(y_tr), X_test=signal(u_te), y_test=signal(y_te), skip=skip,
        sampling_time=ts, unit=unit, report_unit=report_unit, report_scale=scale, name=name, DESCR=descr,
    )


def from_io_data(data):
    """Signals in the library's layout from the official loader's objects.

    Parameters
    ----------
    data : Input_output_data or sequence of them
        Objects of the ``nonlinear-benchmarks`` package (anything with
        attributes ``u`` and ``y``, one sample per row;
        ``state_initialization_window_length`` is read when present).

    Returns
    -------
    X, y : list of ndarray of shape (n_samples, n_inputs) / (n_samples, n_outputs)
        One signal per object (lengths may differ).
    skip : int
        The largest state-initialisation window of the objects (0 when none
        is set): the samples the official score leaves out.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> record = SimpleNamespace(u=np.zeros(100), y=np.ones(100), state_initialization_window_length=50)
    >>> X, y, skip = from_io_data(record)
    >>> X[0].shape, y[0].shape, skip
    ((100, 1), (100, 1), 50)
    """
    items = [data] if hasattr(data, "u") and hasattr(data, "y") else list(data)
    if not items or not all(hasattr(d, "u") and hasattr(d, "y") for d in items):
        raise TypeError("data must be an Input_output_data object (attributes u and y) or a sequence of them.")
    as_2d = lambda v: np.asarray(v, dtype=np.float64).reshape(len(v), -1)  # noqa: E731
    X = [as_2d(d.u) for d in items]
    y = [as_2d(d.y) for d in items]
    skip = max(int(getattr(d, "state_initialization_window_length", None) or 0) for d in items)
    return X, y, skip
