"""Where the gap lies: frequency, amplitude, the (displacement, velocity)
plane and time.

Everything is computed on the validation signals against the noise floor
of the training periods; the nonlinear distortion level comes from the
spread of the training realisations around their best linear approximation.
"""
import numpy as np
from scipy import stats
from scipy.signal import hilbert

from ..frequency.bla import excited_lines, periodic_bla
from ..utils.validation import is_periodic
from .readings import content_limit, missing_force, periods_of, signal_derivative
from .results import (AmplitudeGap, Band, Drift, ForceMap, FrequencyGap, GapLocation, InputLevel, LevelBin, LevelGap,
                      LineKindGap, MotionSamples, SweepGap, SweepWindow, TimeGap)

__all__ = ["locate_gap"]

N_BANDS = 8
N_LEVELS = 8
MAP_BINS = 12
MIN_PER_CELL = 20
N_WINDOWS = 40


def _frequency_analysis(u_list, y_list, y_nominal, n_periods, period, fs, noise, significance,
                        u_train, y_train):
    """Gap spectrum of the periodic validation signals per band and line kind."""
    picks = [i for i, P in enumerate(n_periods) if P]
    if not picks or noise is None:
        return None
    U = np.stack([np.fft.rfft(periods_of(u_list[i], n_periods[i], period).mean(0)) for i in picks])
    E = np.stack([np.fft.rfft(periods_of(y_list[i] - y_nominal[i], n_periods[i], period).mean(0))
                  for i in picks]) / np.sqrt(period)
    P = np.array([n_periods[i] for i in picks], float)[:, None]
    lines = excited_lines(U[:, :, None])
    n_bins = period // 2 + 1
    kind = np.zeros(n_bins, int)  # 0 DC, 1 excited, 2 odd, 3 even (not excited)
    kind[1:] = np.where(np.arange(1, n_bins) % 2 == 1, 2, 3)
    kind[lines] = 1
    gap_power = np.mean(np.abs(E) ** 2, axis=0)
    noise_power = np.mean(noise.spectrum[None, :] / P, axis=0)
    # per line: |E|^2 / (noise / P) is exponential(1) under "no gap"
    stat = np.abs(E) ** 2 / np.maximum(noise.spectrum[None, :] / P, 1e-300)
    p_line = stats.gamma.sf(stat.sum(axis=0), a=len(picks))
    n_tested = n_bins - 1
    significant = p_line < significance / n_tested
    significant[0] = False
    distortion = _distortion_level(u_train, y_train, period, n_bins)
    f = np.fft.rfftfreq(period, 1 / fs)
    f_hi = content_limit([u_list[i] for i in picks], fs)
    edges = np.linspace(0, f_hi, N_BANDS + 1)
    bands = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (f > lo) & (f <= hi)
        bands.append(Band(float(lo), float(hi), _db(gap_power[sel].sum()), _db(noise_power[sel].sum()),
                          None if distortion is None else _db(distortion[sel].sum()), int(sel.sum()),
                          int(significant[sel].sum())))
    by_kind = {}
    names = {1: "excited", 2: "odd_not_excited", 3: "even_not_excited"}
    for k, name in names.items():
        sel = kind == k
        if sel.any():
            by_kind[name] = LineKindGap(int(sel.sum()), int(significant[sel].sum()), _db(gap_power[sel].sum()),
                                        _db(noise_power[sel].sum()))
    has_detection = (kind[: int(f_hi / fs * period)] > 1).sum() > 0.2 * lines.size
    return FrequencyGap(f, gap_power, noise_power, distortion, kind, significant, bands, by_kind,
                        bool(has_detection))


def _distortion_level(u_list, y_list, period, n_bins):
    """Output power of the stochastic nonlinear distortions per bin, from the
    training realisations around their BLA (None without two realisations
    of two periods)."""
    sel = [i for i, u in enumerate(u_list) if is_periodic(u.size, period) and u.size >= 2 * period]
    if len(sel) < 2:
        return None
    Up = [u_list[i].reshape(-1, period, 1) for i in sel]
    Yp = [y_list[i].reshape(-1, period, 1) for i in sel]
    try:
        bla = periodic_bla(Up, Yp)
    except ValueError:
        return None
    U = np.mean([np.abs(np.fft.rfft(u.mean(0)[:, 0])) ** 2 for u in Up], axis=0) / period
    out = np.zeros(n_bins)
    out[bla.lines] = bla.var_nonlinear[:, 0, 0] * len(sel) * U[bla.lines]
    return out


def _db(x):
    return float(10 * np.log10(max(float(x), 1e-300)))


def _amplitude_analysis(u_list, y_list, y_nominal, velocity, noise, train):
    """Gap rms against displacement and velocity level (quantile bins);
    ``train`` is ``(u, y, y_nominal)`` of the training signals."""
    e = np.concatenate([a - b for a, b in zip(y_list, y_nominal)])
    noise_db = _db(noise.variance) if noise is not None else None
    by_level = []
    for x in (np.concatenate(y_list), np.concatenate(velocity)):
        edges = np.quantile(np.abs(x), np.linspace(0, 1, N_LEVELS + 1))
        idx = np.clip(np.searchsorted(edges, np.abs(x), side="right") - 1, 0, N_LEVELS - 1)
        rows = []
        for b in range(N_LEVELS):
            m = idx == b
            rows.append(LevelBin(float(edges[b]), float(edges[b + 1]), _db(np.mean(e[m] ** 2)) if m.any() else None))
        by_level.append(LevelGap(rows, noise_db))
    # Input levels: the relative gap per distinct input rms, training and
    # validation together (a gap growing with level is nonlinear).
    levels = []
    for tag, (us, ys, ns) in (("train", train), ("validation", (u_list, y_list, y_nominal))):
        for u, y, yn in zip(us, ys, ns):
            levels.append(InputLevel(tag, float(np.sqrt(np.mean(u**2))),
                                     _db(np.mean((y - yn) ** 2) / np.mean(y**2))))
    rms = np.array([lv.input_rms for lv in levels])
    return AmplitudeGap(*by_level, levels, bool(rms.max() > 1.2 * rms.min()))


def _force_map(nominal, u_list, y_list, n_periods, period, fs, f_max):
    """Mean missing force (see :func:`missing_force`) over the
    (displacement, velocity) plane; stateful nominal elements are flagged."""
    y, v, _, f = missing_force(nominal, u_list, y_list, n_periods, period, fs, f_max)
    y_edges = np.linspace(y.min(), y.max(), MAP_BINS + 1)
    v_edges = np.linspace(v.min(), v.max(), MAP_BINS + 1)
    iy = np.clip(np.searchsorted(y_edges, y, side="right") - 1, 0, MAP_BINS - 1)
    iv = np.clip(np.searchsorted(v_edges, v, side="right") - 1, 0, MAP_BINS - 1)
    total = np.zeros((MAP_BINS, MAP_BINS))
    count = np.zeros((MAP_BINS, MAP_BINS))
    np.add.at(total, (iy, iv), f)
    np.add.at(count, (iy, iv), 1)
    force = np.where(count >= MIN_PER_CELL, total / np.maximum(count, 1), np.nan)
    return ForceMap(y_edges, v_edges, force, count, float(np.sqrt(np.mean(f**2))),
                    bool(any(e.n_states for e in nominal.forces)), MotionSamples(y, v, f))


def _time_analysis(u_list, y_list, y_nominal, n_periods, period, fs, noise, y_train):
    """Gap over time: along sweeps (against the instantaneous frequency of
    the input) and from period to period of the training signals (drift)."""
    sweeps = []
    for i, (u, y, yn, P) in enumerate(zip(u_list, y_list, y_nominal, n_periods)):
        if P or u.size < 4 * N_WINDOWS:
            continue
        phase = np.unwrap(np.angle(hilbert(u - u.mean())))
        inst_f = np.gradient(phase) * fs / (2 * np.pi)
        edges = np.linspace(0, u.size, N_WINDOWS + 1).astype(int)
        rows = []
        for a, b in zip(edges[:-1], edges[1:]):
            rows.append(SweepWindow(float((a + b) / 2 / fs), float(np.median(inst_f[a:b])),
                                    _db(np.mean((y[a:b] - yn[a:b]) ** 2)), _db(np.mean(y[a:b] ** 2))))
        sweeps.append(SweepGap(i, rows))
    # Drift: how much the measured response changes from the first period,
    # against what noise alone gives (2 sigma^2 per sample).
    drift = None
    changes = []
    for y in y_train:
        if is_periodic(y.size, period) and y.size >= 3 * period:
            Yp = periods_of(y, y.size // period, period)
            changes.append([np.mean((Yp[p] - Yp[0]) ** 2) for p in range(1, Yp.shape[0])])
    if changes and noise is not None:
        width = min(len(c) for c in changes)
        mean_change = np.mean([c[:width] for c in changes], axis=0)
        ratio = mean_change / (2 * noise.variance)
        slope = np.polyfit(np.arange(1, width + 1), ratio, 1)[0] if width > 1 else 0.0
        drift = Drift([_db(r) for r in ratio], float(slope), bool(ratio[-1] > 2.0))
    return TimeGap(sweeps, drift)


def locate_gap(nominal, u_list, y_list, y_nominal, n_periods, *, fs, period, noise, significance,
               u_train, y_train, y_train_nominal):
    """Where a nominal simulator misses validation signals.

    The "where" analysis of :class:`~sklearn_pnlss.gap.GapDiagnosis`, which
    calls it with its fitted noise floor and training signals.

    Parameters
    ----------
    nominal : Oscillator
        The nominal simulator (its equation of motion gives the missing
        force).
    u_list, y_list : list of ndarray (n_samples_i,)
        Validation input forces and measured displacements.
    y_nominal : list of ndarray (n_samples_i,)
        The nominal simulation of each validation signal.
    n_periods : list of int
        Steady-state periods of each validation signal (0: from rest), as
        in :class:`~sklearn_pnlss.gap.fitting.simulate.SignalSet`.
    fs : float
        Sampling rate, Hz.
    period : int or None
        Samples per period of the periodic signals.
    noise : NoiseFloor or None
        Noise floor of the training periods (see
        :func:`~sklearn_pnlss.gap.verdict.noise_floor.estimate_noise`); without it there
        is no frequency analysis and no drift reading.
    significance : float
        Level of the per-line test of the gap against the noise floor
        (Bonferroni over the lines).
    u_train, y_train : list of ndarray (n_samples_i,)
        Training input forces and measured displacements: their
        realisations give the nonlinear distortion level, their periods the
        drift, their input levels a point each of the gap against level.
    y_train_nominal : list of ndarray (n_samples_i,)
        The nominal simulation of each training signal.

    Returns
    -------
    where : GapLocation
        ``frequency`` (bands, line kinds, per-line significance; None
        without periodic validation signals or noise floor), ``amplitude``
        (gap per displacement / velocity level, per input level),
        ``state_plane`` (missing-force map) and ``time`` (sweeps, drift);
        see :mod:`sklearn_pnlss.gap.results`.
    """
    f_max = content_limit(u_list, fs)
    velocity = [signal_derivative(y, fs, P, period, 1, f_max) for y, P in zip(y_list, n_periods)]
    return GapLocation(
        frequency=_frequency_analysis(u_list, y_list, y_nominal, n_periods, period, fs, noise, significance,
                                      u_train, y_train),
        amplitude=_amplitude_analysis(u_list, y_list, y_nominal, velocity, noise,
                                      (u_train, y_train, y_train_nominal)),
        state_plane=_force_map(nominal, u_list, y_list, n_periods, period, fs, f_max),
        time=_time_analysis(u_list, y_list, y_nominal, n_periods, period, fs, noise, y_train),
    )
