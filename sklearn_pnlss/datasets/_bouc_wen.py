"""The Bouc-Wen hysteresis benchmark: simulator, generated data, official files."""
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.utils import Bunch, check_random_state

from ..physics import BoucWen, Oscillator, band_limited_noise, decimate_fir, upsample_fft
from ..physics.resampling import check_signal
from ..signals import bouc_wen_sweep, multisine

__all__ = ["bouc_wen_oscillator", "simulate_bouc_wen", "make_bouc_wen",
           "load_bouc_wen_official"]

FS = 750.0
OVERSAMPLING = 20
PERIOD = 8192
F_BAND = (5.0, 150.0)
SWEEP_DECIMATION = (20,)  # the official sweep file used a single stage
MULTISINE_DECIMATION = (2, 2, 5)

_DESCR_MAKE = """\
Bouc-Wen hysteresis benchmark, simulated
----------------------------------------
m y'' + c y' + k y + z = u,  z' = alpha y' - beta (gamma |y'| |z|^(nu-1) z
+ delta y' |z|^nu), with m=2, c=10, k=5e4, alpha=5e4, beta=1e3, gamma=0.8,
delta=-1.1, nu=1; y in m, u in N, fs = 750 Hz.

Simulated as the official data: Newmark (1/2, 1/4) + trapezoidal rule at
15 kHz with converged Newton-Raphson, FIR decimation (MATLAB decimate).

X_train, y_train : (n_realizations, n_periods * 8192, 1) steady-state
    periodic full random-phase multisines 5-150 Hz; output noise band-limited
    to 0-375 Hz added at 15 kHz before the 2-2-5 decimation chain,
    independent over the whole record.
X_test_multisine, y_test_multisine : (1, 8192, 1) a fresh noiseless
    realisation, one steady-state period.
X_test_sweep, y_test_sweep : (1, 153000, 1) the benchmark sweep
    40 sin(2 pi (18 t + t^2/12)) from rest, noiseless, single-stage decimation.
X_test, y_test : lists of the two 2-D test signals [(8192, 1), (153000, 1)].
lines : excited DFT bins of the multisines (f = k fs / period).
"""

_DESCR_OFFICIAL = """\
Bouc-Wen hysteresis benchmark, official files
---------------------------------------------
X_train, y_train : (1, 32768, 1) periods 2-5 of train_multisine_official.mat
    (steady state; output noisy, about 7.4e-6 m rms).
X_train_raw, y_train_raw : (1, 40960, 1) all 5 periods (the first holds the
    transient from rest).
X_test_multisine, y_test_multisine : (1, 8192, 1) uval/yval_multisine.mat.
X_test_sweep, y_test_sweep : (1, 153000, 1) uval/yval_sinesweep.mat.
X_test, y_test : lists of the two 2-D test signals.
Never use the test data for estimation.
"""


def bouc_wen_oscillator():
    """The benchmark system as an :class:`~sklearn_pnlss.physics.Oscillator`.

    Returns
    -------
    oscillator : Oscillator
        ``m = 2``, ``c = 10``, ``k = 5e4`` and ``BoucWen()`` with the
        benchmark's ``alpha, beta, gamma, delta, nu = 5e4, 1e3, 0.8, -1.1, 1``.

    Examples
    --------
    >>> from sklearn_pnlss.datasets import bouc_wen_oscillator
    >>> bouc_wen_oscillator().mass
    2.0
    """
    return Oscillator(2.0, 10.0, 5e4, forces=(BoucWen(5e4, 1e3, 0.8, -1.1, 1.0),))


def simulate_bouc_wen(u, *, periodic, decimation=(2, 2, 5), noise_rms=0.0,
                      random_state=None):
    """Simulate the Bouc-Wen benchmark system as the official data were.

    The 750 Hz input is interpolated to 15 kHz by FFT, integrated (Newmark +
    trapezoidal rule, converged Newton-Raphson), optional noise is added at
    15 kHz and the output is decimated with MATLAB-compatible FIR filters.

    Parameters
    ----------
    u : array-like of shape (n_samples,)
        Input force at 750 Hz, N.  One period of a periodic input when
        ``periodic`` is True.
    periodic : bool
        True: steady-state periodic response (one period, decimated
        circularly).  False: response from rest at ``t = 0``.
    decimation : sequence of int, default=(2, 2, 5)
        FIR decimation chain from 15 kHz to 750 Hz (product 20).  The
        official multisines used ``(2, 2, 5)``, the official sweep ``(20,)``.
    noise_rms : float, default=0.0
        Rms at 15 kHz of Gaussian output noise band-limited to 0-375 Hz,
        added before decimation (8e-6 gives about 7.4e-6 m after it).
    random_state : int, RandomState instance or None, default=None
        Seed of the noise.

    Returns
    -------
    y : ndarray of shape (n_samples,)
        Displacement at 750 Hz, m.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.datasets import simulate_bouc_wen
    >>> from sklearn_pnlss.signals import multisine
    >>> X, _ = multisine(1024, rms=50.0, random_state=0)
    >>> y = simulate_bouc_wen(X[0, :, 0], periodic=True)
    >>> y.shape
    (1024,)
    """
    u = check_signal(u, "u")
    return bouc_wen_oscillator().simulate(
        u, fs=FS, periodic=periodic, oversampling=OVERSAMPLING, decimation=decimation,
        noise_rms=noise_rms, random_state=random_state,
    )


def _steady_state_period(osc, u_period):
    fine = osc.simulate_fine(upsample_fft(u_period, OVERSAMPLING, periodic=True),
                             fs=FS * OVERSAMPLING, periodic=True)
    return decimate_fir(fine.y, MULTISINE_DECIMATION, periodic=True)


def make_bouc_wen(n_realizations=2, n_periods=2, rms=50.0, noise_rms=8e-6,
                  random_state=None, *, n_samples=PERIOD, f_band=F_BAND, n_jobs=None):
    """Generate Bouc-Wen benchmark data with the official simulator's recipe.

    Parameters
    ----------
    n_realizations : int, default=2
        Training multisine realisations.
    n_periods : int, default=2
        Steady-state periods per training realisation.
    rms : float, default=50.0
        Input rms of every multisine (training and test), N.
    noise_rms : float, default=8e-6
        Rms at 15 kHz of the band-limited (0-375 Hz) training output noise,
        before decimation (about 7.4e-6 m after).  Test outputs are noiseless.
    random_state : int, RandomState instance or None, default=None
        Seed of the phases and the noise.
    n_samples : int, default=8192
        Samples per multisine period.
    f_band : tuple of float, default=(5.0, 150.0)
        Excited band of the multisines, Hz.
    n_jobs : int or None, default=None
        Threads for the realisations (the compiled integrator releases the
        GIL); None means 1.

    Returns
    -------
    data : :class:`~sklearn.utils.Bunch`
        ``X_train, y_train`` (n_realizations, n_periods * n_samples, 1);
        ``X_test_multisine, y_test_multisine`` (1, n_samples, 1);
        ``X_test_sweep, y_test_sweep`` (1, 153000, 1); ``X_test, y_test``
        (lists of the two 2-D test signals); ``fs``, ``period``, ``lines``,
        ``DESCR``.

    Examples
    --------
    >>> from sklearn_pnlss.datasets import make_bouc_wen
    >>> data = make_bouc_wen(n_realizations=1, n_periods=1, random_state=0)
    >>> data.X_train.shape, data.y_test_sweep.shape
    ((1, 8192, 1), (1, 153000, 1))
    """
    for name, value in (("n_realizations", n_realizations), ("n_periods", n_periods)):
        if isinstance(value, bool) or not isinstance(value, Integral) or value < 1:
            raise ValueError(f"{name} must be a positive int, got {value!r}.")
    if not np.isfinite(noise_rms) or noise_rms < 0:
        raise ValueError(f"noise_rms must be a finite number >= 0, got {noise_rms!r}.")
    rng = check_random_state(random_state)
    osc = bouc_wen_oscillator()

    # One draw for training and test phases keeps the test realisation
    # independent of, yet reproducible with, the training ones.
    X_all, lines = multisine(n_samples, fs=FS, f_band=f_band, rms=rms, kind="full",
                             n_realizations=n_realizations + 1, random_state=rng)
    periods = [X_all[r, :, 0] for r in range(n_realizations + 1)]
    noise_seeds = rng.randint(np.iinfo(np.int32).max, size=n_realizations)

    n_threads = 1 if n_jobs is None else int(n_jobs)
    if n_threads == -1:
        import os
        n_threads = os.cpu_count() or 1
    if n_threads > 1:
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(max_workers=n_threads) as pool:
            steady = list(pool.map(lambda p: _steady_state_period(osc, p), periods))
    else:
        steady = [_steady_state_period(osc, p) for p in periods]

    n_fine = n_periods * n_samples * OVERSAMPLING
    X_train = np.tile(X_all[:n_realizations], (1, n_periods, 1))
    y_train = np.empty_like(X_train)
    for r in range(n_realizations):
        y = np.tile(steady[r], n_periods)
        if noise_rms > 0:
            # Decimation is linear and the steady record periodic, so the
            # noise can be decimated on its own (circularly, over the record).
            noise = band_limited_noise(n_fine, fs=FS * OVERSAMPLING, f_max=FS / 2,
                                       rms=noise_rms, random_state=int(noise_seeds[r]))
            y = y + decimate_fir(noise, MULTISINE_DECIMATION, periodic=True)
        y_train[r, :, 0] = y

    X_ms = X_all[n_realizations:].copy()
    y_ms = steady[n_realizations][None, :, None].copy()

    n_sweep = 153000
    u_sweep = bouc_wen_sweep(n_sweep, FS)
    u_sweep_fine = bouc_wen_sweep(n_sweep, FS, oversampling=OVERSAMPLING)
    y_sweep = osc.simulate(u_sweep, fs=FS, periodic=False, oversampling=OVERSAMPLING,
                           decimation=SWEEP_DECIMATION, u_fine=u_sweep_fine)
    X_sw = u_sweep[None, :, None]
    y_sw = y_sweep[None, :, None]

    return Bunch(
        X_train=X_train, y_train=y_train,
        X_test_multisine=X_ms, y_test_multisine=y_ms,
        X_test_sweep=X_sw, y_test_sweep=y_sw,
        X_test=[X_ms[0], X_sw[0]], y_test=[y_ms[0], y_sw[0]],
        fs=FS, period=int(n_samples), lines=lines, DESCR=_DESCR_MAKE,
    )


def _load_vector(folder, filename, key):
    from scipy.io import loadmat

    path = folder / filename
    if not path.is_file():
        raise FileNotFoundError(
            f"Bouc-Wen file {filename!r} not found in folder {str(folder)!r}."
        )
    content = loadmat(path)
    if key not in content:
        raise KeyError(f"variable {key!r} missing from {str(path)!r}.")
    return np.asarray(content[key], dtype=np.float64).ravel()


def load_bouc_wen_official(data_dir):
    """Load the official Bouc-Wen benchmark files into the library's layout.

    Parameters
    ----------
    data_dir : str or path-like
        Folder with ``uval_multisine.mat``, ``yval_multisine.mat``,
        ``uval_sinesweep.mat``, ``yval_sinesweep.mat`` and
        ``train_multisine_official.mat``.

    Returns
    -------
    data : :class:`~sklearn.utils.Bunch`
        ``X_train, y_train`` (1, 32768, 1): periods 2-5 of the training
        record (steady state); ``X_train_raw, y_train_raw`` (1, 40960, 1):
        all 5 periods; ``X_test_multisine, y_test_multisine`` (1, 8192, 1);
        ``X_test_sweep, y_test_sweep`` (1, 153000, 1); ``X_test, y_test``
        (lists of the two 2-D test signals); ``fs``, ``period``, ``lines``
        (bins excited in the training input), ``DESCR``.

    Raises
    ------
    FileNotFoundError
        If a file is missing (the message names the file and the folder).

    Examples
    --------
    >>> from sklearn_pnlss.datasets import load_bouc_wen_official
    >>> data = load_bouc_wen_official("path/to/bouc_wen")  # doctest: +SKIP
    >>> data.X_train.shape  # doctest: +SKIP
    (1, 32768, 1)
    """
    folder = Path(data_dir)
    u_ms = _load_vector(folder, "uval_multisine.mat", "uval_multisine")
    y_ms = _load_vector(folder, "yval_multisine.mat", "yval_multisine")
    u_sw = _load_vector(folder, "uval_sinesweep.mat", "uval_sinesweep")
    y_sw = _load_vector(folder, "yval_sinesweep.mat", "yval_sinesweep")
    u_tr = _load_vector(folder, "train_multisine_official.mat", "u")
    y_tr = _load_vector(folder, "train_multisine_official.mat", "y")
    fs = float(_load_vector(folder, "train_multisine_official.mat", "fs")[0])

    period = PERIOD
    spec = np.abs(np.fft.rfft(u_tr[:period]))
    lines = np.flatnonzero(spec > 1e-6 * spec.max())
    lines = lines[lines > 0]

    def col(v):
        return v[None, :, None]

    return Bunch(
        X_train=col(u_tr[period:]), y_train=col(y_tr[period:]),
        X_train_raw=col(u_tr), y_train_raw=col(y_tr),
        X_test_multisine=col(u_ms), y_test_multisine=col(y_ms),
        X_test_sweep=col(u_sw), y_test_sweep=col(y_sw),
        X_test=[u_ms[:, None], u_sw[:, None]], y_test=[y_ms[:, None], y_sw[:, None]],
        fs=fs, period=period, lines=lines, DESCR=_DESCR_OFFICIAL,
    )
