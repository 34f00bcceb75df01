"""The F-16 ground vibration test benchmark: loader of the measured files."""
import os
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.utils import Bunch

__all__ = ["load_f16"]

FS = 400.0
ENV_VAR = "SKLEARN_PNLSS_F16_DATA"

# kind -> (tag in the file names, samples per period or None, levels,
#          periods dropped as transient at the start of every realisation)
_KINDS = {
    "multisine": ("FullMSine", 8192, range(1, 8), 1),
    "sinesweep": ("SineSw", None, range(1, 8), 0),
    "special_odd": ("SpecialOddMSine", 16384, range(1, 4), 1),
}
# Force levels of the benchmark description (N rms for the multisines, N
# amplitude for the sweeps).
FORCE_LEVELS = {
    "multisine": {1: 12.4, 2: 24.6, 3: 36.8, 4: 61.4, 5: 73.6, 6: 85.7, 7: 97.8},
    "sinesweep": {1: 4.8, 2: 19.2, 3: 28.8, 4: 57.6, 5: 67.0, 6: 86.0, 7: 95.6},
    "special_odd": {1: 12.2, 2: 49.0, 3: 97.1},
}
# Test level paired with each estimation level (the benchmark tests models of
# levels 3, 5, 7 on 2, 4, 6; level 1, linear, is paired with the nearest, 2).
_PAIRED = {1: 2, 3: 2, 5: 4, 7: 6}
OUTPUT_NAMES = (
    "excitation location",
    "right wing, next to the payload interface",
    "payload, next to the same interface",
)

_DESCR = """\
F-16 ground vibration test benchmark (Noel & Schoukens, 2017)
------------------------------------------------------------
A full-scale F-16 with two dummy payloads at the wing tips, excited by one
shaker under the right wing (Siemens LMS Ground Vibration Testing Master
Class, September 2014, Saffraanberg military base, Sint-Truiden, Belgium).
Input: the shaker force (N) measured by an impedance head. Outputs: three
accelerations, (1) at the excitation location, (2) on the right wing next to
the right-wing-to-payload interface, (3) on the payload next to the same
interface. fs = 400 Hz. The main nonlinearity is the back connection of that
interface (clearance and friction); about 10 modes lie in 2-15 Hz, the wing
torsion mode near 7.3 Hz carries the strongest distortion.

Records (levels 1-7; the odd levels are for estimation, the even ones,
files *_Validation.mat, test the models of levels 3, 5, 7):
multisine   full-grid random-phase multisine 2-15 Hz, one realisation of
            9 periods of 8192 samples per level; the first period holds
            the transient and is dropped (X, y hold periods 2-9).
            12.4, 24.6, 36.8, 61.4, 73.6, 85.7, 97.8 N rms.
sinesweep   sweep down 15 -> 2 Hz at 0.05 Hz/s, from rest; the exact-zero
            padding at the end of the files is removed.
            4.8, 19.2, 28.8, 57.6, 67.0, 86.0, 95.6 N amplitude.
special_odd random-odd multisine 1-60 Hz (one odd line in four left out),
            10 realisations of 3 periods of 16384 samples at levels 1-3
            (12.2, 49.0, 97.1 N rms), 9 realisations in
            *_Level#.mat and the tenth in *_Level#_Validation.mat; the
            first period is dropped. Recorded at 200 Hz and upsampled to
            400 Hz in the frequency domain by the benchmark's authors.

Source: nonlinearbenchmark.org (F-16 GVT); J.P. Noel and M. Schoukens,
"F-16 aircraft benchmark based on ground vibration test data", Workshop on
Nonlinear System Identification Benchmarks, Brussels, 2017.
"""


def _data_folder(path):
    if path is None:
        path = os.environ.get(ENV_VAR)
        if not path:
            raise FileNotFoundError(
                "No folder for the F-16 benchmark files: pass path= to load_f16 or set "
                f"the environment variable {ENV_VAR} to the folder holding the "
                "F16Data_*.mat files (BenchmarkData of F16GVT_Files.zip from "
                "nonlinearbenchmark.org)."
            )
    folder = Path(path).expanduser()
    # The benchmark's archive unpacks to F16GVT_Files/BenchmarkData.
    for candidate in (folder, folder / "BenchmarkData", folder / "F16GVT_Files" / "BenchmarkData"):
        if any(candidate.glob("F16Data_*")):
            return candidate
    return folder


def _file_stem(kind, level, validation):
    tag = _KINDS[kind][0]
    return f"F16Data_{tag}_Level{level}" + ("_Validation" if validation else "")


def _read_record(folder, stem, kind, source):
    """Force, voltage (R, n) and accelerations (R, n, 3) of one file."""
    mat, csv = folder / f"{stem}.mat", folder / f"{stem}.csv"
    if mat.is_file():
        from scipy.io import loadmat

        content = loadmat(mat)
        missing = [k for k in ("Force", "Voltage", "Acceleration") if k not in content]
        if missing:
            raise KeyError(f"variable(s) {missing} missing from {str(mat)!r}.")
        force = np.atleast_2d(np.asarray(content["Force"], dtype=np.float64))
        voltage = np.atleast_2d(np.asarray(content["Voltage"], dtype=np.float64))
        acc = np.asarray(content["Acceleration"], dtype=np.float64)
        if acc.ndim == 2:  # (3, n): one realisation
            acc = acc[:, None, :]
        acc = acc.transpose(1, 2, 0)  # (R, n, 3)
        if "Fs" in content and float(np.ravel(content["Fs"])[0]) != FS:
            raise ValueError(f"{str(mat)!r} is sampled at {float(np.ravel(content['Fs'])[0])} Hz, not {FS}.")
    elif csv.is_file():
        table = np.genfromtxt(csv, delimiter=",", names=True)
        names = table.dtype.names
        needed = ("Force", "Voltage", "Acceleration1", "Acceleration2", "Acceleration3")
        if not set(needed) <= set(names):
            raise KeyError(f"{str(csv)!r} lacks the columns {needed}; it has {names}.")
        if kind == "special_odd":
            raise ValueError(
                f"{str(csv)!r}: the multi-realisation special_odd records are read from the "
                ".mat files only."
            )
        force = table["Force"][None]
        voltage = table["Voltage"][None]
        acc = np.stack([table[f"Acceleration{i}"] for i in (1, 2, 3)], axis=-1)[None]
    else:
        raise FileNotFoundError(
            f"F-16 benchmark file {stem}.mat (or .csv) not found in {str(folder)!r} "
            f"(folder from {source}). Pass path= to load_f16 or set {ENV_VAR} to the folder "
            "holding the F16Data_*.mat files."
        )
    if force.shape != voltage.shape or force.shape != acc.shape[:2]:
        raise ValueError(
            f"{stem}: force {force.shape}, voltage {voltage.shape} and accelerations "
            f"{acc.shape} do not describe the same samples."
        )
    return force, voltage, acc


def _layout(force, voltage, acc, kind):
    """Steady-state (or trimmed) signals in the library's layout."""
    _, period, _, n_drop = _KINDS[kind]
    raw = (force[..., None], voltage[..., None], acc)
    if period is None:
        # Sweeps: the files end with exact zeros in every channel (padding).
        active = np.flatnonzero((force[0] != 0) | (voltage[0] != 0) | np.any(acc[0] != 0, axis=-1))
        end = active[-1] + 1 if active.size else 0
        return tuple(a[:, :end] for a in raw), raw
    n = force.shape[1]
    if n % period:
        raise ValueError(f"a {kind} record has {n} samples, not a multiple of {period}.")
    return tuple(a[:, n_drop * period:] for a in raw), raw


def _excited_lines_of(X, period):
    from ..frequency.bla import DETECTION_GAP_DB, excited_lines

    n_per = X.shape[1] // period
    U = np.fft.rfft(X.reshape(X.shape[0], n_per, period, X.shape[2]).mean(axis=1), axis=1)
    return excited_lines(U, gap_db=DETECTION_GAP_DB)


def load_f16(path=None, *, level=3, kind="multisine", validation_level="paired"):
    """Load the F-16 ground vibration test benchmark into the library's layout.

    Measured data from a real structure: a full-scale F-16 with dummy
    payloads at the wing tips, one shaker under the right wing (input: the
    measured force, N) and three accelerations (outputs: at the excitation,
    on the right wing next to the payload interface, on the payload next to
    it), 400 Hz. The nonlinearity is the bolted wing-to-payload interface
    (clearance and friction). The files are not shipped with the library:
    download ``F16GVT_Files.zip`` from nonlinearbenchmark.org (or take the
    ``F16Data_*.mat`` files from a copy) and point ``path`` or the
    environment variable ``SKLEARN_PNLSS_F16_DATA`` at them.

    Parameters
    ----------
    path : str, path-like or None, default=None
        Folder with the ``F16Data_*.mat`` files (``.csv`` are read too, except
        for ``kind="special_odd"``); the archive's ``BenchmarkData`` or
        ``F16GVT_Files/BenchmarkData`` subfolders are looked into. None reads
        the folder from ``SKLEARN_PNLSS_F16_DATA``.
    level : int, default=3
        Excitation level: 1-7 for ``"multisine"`` and ``"sinesweep"``
        (odd levels are the estimation sets, even ones the test sets), 1-3
        for ``"special_odd"``.
    kind : {"multisine", "sinesweep", "special_odd"}, default="multisine"
        ``"multisine"``: full-grid random-phase multisine 2-15 Hz, one
        realisation of 9 periods of 8192 samples (``F16Data_FullMSine_*``).
        ``"sinesweep"``: sweep down 15 to 2 Hz at 0.05 Hz/s from rest
        (``F16Data_SineSw_*``). ``"special_odd"``: random-odd multisine 1-60
        Hz, 3 periods of 16384 samples per realisation
        (``F16Data_SpecialOddMSine_*``).
    validation_level : "paired", int or None, default="paired"
        Level of the test record returned as ``X_val, y_val`` (same kind).
        ``"paired"``: the benchmark's pairing, level 2 for 1 and 3, 4 for 5,
        6 for 7, none for an even (test) level; for ``"special_odd"`` the
        ``*_Validation`` file of the same level (the tenth realisation).
        None loads no test record.

    Returns
    -------
    data : :class:`~sklearn.utils.Bunch`
        ``X`` (n_signals, n_samples, 1) force and ``y`` (n_signals,
        n_samples, 3) accelerations, laid out as the estimators expect:

        - ``"multisine"``: (1, 65536, ·), periods 2-9; the first period holds
          the transient from the start of the excitation and is dropped.
        - ``"special_odd"``: (R, 32768, ·), periods 2-3 of each of the R
          realisations (R = 9 in the estimation files, 1 in the test file);
          the first period is dropped as transient.
        - ``"sinesweep"``: (1, n, ·) from rest, ``n`` up to the last nonzero
          sample (the files end with exact zero padding).

        ``X_raw, y_raw``: the records as stored (all periods, padding).
        ``voltage``: the signal generator's voltage (the reference input),
        laid out as ``X``. ``X_val, y_val``: the test record of
        ``validation_level`` in the same layout (None when there is none).
        ``fs`` (400.0), ``period`` (8192, 16384, or None for the sweep),
        ``lines`` (excited DFT bins of one period, detected in the force
        spectrum as :class:`~sklearn_pnlss.BLAEstimator` does: bins 41-307,
        2-15 Hz, for the full multisine; None for the sweep), ``level``, ``validation_level``, ``kind``,
        ``force_level`` (the nominal level of the description, N rms for the
        multisines, N amplitude for the sweep), ``output_names``,
        ``DESCR``.

    Raises
    ------
    FileNotFoundError
        If no folder is given (neither ``path`` nor
        ``SKLEARN_PNLSS_F16_DATA``) or a needed file is missing; the message
        names the file, the folder, ``path`` and the environment variable.

    Notes
    -----
    J.P. Noel and M. Schoukens, "F-16 aircraft benchmark based on ground
    vibration test data", 2017 Workshop on Nonlinear System Identification
    Benchmarks, Brussels, Belgium (nonlinearbenchmark.org). Test models of
    levels 3, 5 and 7 on levels 2, 4 and 6 by the rms of the simulation
    error, per output or over the outputs.

    Examples
    --------
    >>> from sklearn_pnlss.datasets import load_f16
    >>> data = load_f16("path/to/F16GVT_Files/BenchmarkData")  # doctest: +SKIP
    >>> data.X.shape, data.y.shape, data.period, data.validation_level  # doctest: +SKIP
    ((1, 65536, 1), (1, 65536, 3), 8192, 2)
    """
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {sorted(_KINDS)}; got {kind!r}.")
    levels = _KINDS[kind][2]
    if isinstance(level, bool) or not isinstance(level, Integral) or level not in levels:
        raise ValueError(f"level must be an int in {levels.start}..{levels.stop - 1} for kind={kind!r}; got {level!r}.")
    source = "the path argument" if path is not None else f"${ENV_VAR}"
    folder = _data_folder(path)
    period = _KINDS[kind][1]

    if kind == "special_odd":
        main_file = _file_stem(kind, level, validation=False)
        if validation_level == "paired":
            validation_level = level
    else:
        main_file = _file_stem(kind, level, validation=level % 2 == 0)
        if validation_level == "paired":
            validation_level = _PAIRED.get(level)
    (X, V, y), (X_raw, _, y_raw) = _layout(*_read_record(folder, main_file, kind, source), kind)

    X_val = y_val = None
    if validation_level is not None:
        if isinstance(validation_level, bool) or not isinstance(validation_level, Integral) \
                or validation_level not in levels:
            raise ValueError(
                f"validation_level must be 'paired', None or an int in {levels.start}.."
                f"{levels.stop - 1}; got {validation_level!r}."
            )
        validation_level = int(validation_level)
        val_file = (_file_stem(kind, validation_level, validation=True) if kind == "special_odd"
                    else _file_stem(kind, validation_level, validation=validation_level % 2 == 0))
        (X_val, _, y_val), _ = _layout(*_read_record(folder, val_file, kind, source), kind)

    lines = None if period is None else _excited_lines_of(X, period)
    return Bunch(
        X=X, y=y, X_raw=X_raw, y_raw=y_raw, voltage=V, X_val=X_val, y_val=y_val,
        fs=FS, period=period, lines=lines, level=int(level), validation_level=validation_level,
        kind=kind, force_level=FORCE_LEVELS[kind][int(level)], output_names=list(OUTPUT_NAMES),
        DESCR=_DESCR,
    )
