"""Nonparametric best linear approximation (BLA) from periodic data.

The robust method (Pintelon & Schoukens, "System Identification: A Frequency
Domain Approach", ch. 3-4): R realisations of a random-phase multisine, P
steady-state periods each. Per realisation, spectra are averaged over the
periods and the FRF is their ratio; the FRFs are averaged over realisations.
The spread over periods is the noise; the spread over realisations is noise
plus the stochastic nonlinear distortion. Output power at non-excited odd and
even lines reveals odd and even nonlinearities.

Variances are those of the averaged estimate ``G_BLA`` (divide by the number
of averages once more for the level of a single realisation).
"""
from dataclasses import dataclass, field

import numpy as np

__all__ = ["PeriodicBLA", "periodic_bla", "excited_lines", "welch_bla"]


@dataclass
class PeriodicBLA:
    """Result of :func:`periodic_bla` (see its docstring for the fields)."""

    lines: np.ndarray
    frf: np.ndarray
    var_total: np.ndarray
    var_noise: np.ndarray
    var_nonlinear: np.ndarray
    n_realizations: int
    n_periods: int
    output_level: np.ndarray = field(repr=False)
    noise_level: np.ndarray = field(repr=False)
    line_kind: np.ndarray = field(repr=False)


# Detection of the excited lines by periodic_bla (and so BLAEstimator): the
# candidate bins within -60 dB of the strongest lose those below the largest
# drop of at least DETECTION_GAP_DB in their sorted powers, when the bins below
# it carry less than DETECTION_SHARE of the candidates' power.
DETECTION_THRESHOLD_DB = -60.0
DETECTION_GAP_DB = 20.0
DETECTION_SHARE = 1e-2


def excited_lines(U_spectra, threshold_db=DETECTION_THRESHOLD_DB, *, gap_db=None,
                  max_share=DETECTION_SHARE):
    """DFT bins that carry input power, relative to the strongest bin.

    Parameters
    ----------
    U_spectra : ndarray of shape (..., n_bins, m), complex
    threshold_db : float, default=-60.0
        Bins with power within ``threshold_db`` of the strongest are
        candidates (DC never is).
    gap_db : float or None, default=None
        If given, the candidates are sorted by power and split at the largest
        drop between neighbours; when that drop is at least ``gap_db`` and the
        candidates below it carry less than ``max_share`` of the candidates'
        power, they are not excited. A designed multisine has its lines at
        comparable levels; a measured input adds bins far below them that hold
        almost none of its power: leakage of the shaker's interaction, mains
        hum (50 Hz and harmonics), noise. None keeps every candidate.
    max_share : float, default=0.01
        Largest share of the candidates' power the bins below the gap may
        carry to be set aside (``gap_db`` only).

    Returns
    -------
    lines : ndarray of int
        The excited bins, ascending.
    """
    power = np.mean(np.abs(U_spectra) ** 2, axis=tuple(range(U_spectra.ndim - 2)))
    power = power.sum(axis=-1)
    power[0] = 0.0  # DC is never an excited line of a multisine
    lines = np.flatnonzero(power > power.max() * 10 ** (threshold_db / 10))
    if gap_db is None or lines.size < 2:
        return lines
    order = np.argsort(power[lines])[::-1]
    level_db = 10 * np.log10(power[lines][order])
    drops = level_db[:-1] - level_db[1:]
    cut = int(np.argmax(drops))
    below = power[lines][order][cut + 1:]
    if drops[cut] >= gap_db and below.sum() < max_share * power[lines].sum():
        lines = np.sort(lines[order][: cut + 1])
    return lines


def _frf_of_block(U, Y):
    """FRF of one block of m experiments: ``G = Y U^-1`` per line.

    U : (m_exp, K, m), Y : (m_exp, K, p) -> G : (K, p, m)
    """
    Um = U.transpose(1, 2, 0)  # (K, m, m_exp): columns are experiments
    Ym = Y.transpose(1, 2, 0)  # (K, p, m_exp)
    return np.linalg.solve(Um.transpose(0, 2, 1), Ym.transpose(0, 2, 1)).transpose(0, 2, 1)


def periodic_bla(U_periods, Y_periods, lines=None):
    """Nonparametric BLA from steady-state periodic data.

    Parameters
    ----------
    U_periods : list of ndarray of shape (P_r, N, m)
        Input of each realisation, split into its P_r periods of N samples.
    Y_periods : list of ndarray of shape (P_r, N, p)
        Output, likewise.
    lines : array-like of int, default=None
        Excited DFT bins. When None, the bins of the period-averaged input
        spectrum within -60 dB of the strongest, less those below a drop of
        20 dB or more in the sorted bin powers that carry under 1 % of the
        input power (mains hum, leakage, noise of a measured input; see
        :func:`excited_lines`).

    Returns
    -------
    PeriodicBLA
        ``frf`` (K, p, m) at ``lines``; ``var_total`` (noise + nonlinear
        distortion, from the spread over realisation blocks), ``var_noise``
        (from the spread over periods), ``var_nonlinear`` = their difference
        (>= 0), all for the averaged estimate; ``output_level`` and
        ``noise_level`` (n_bins, p): output power and noise power (per period
        average) at every bin 0..N/2; ``line_kind`` (n_bins,): 0 DC or not
        analysed, 1 excited, 2 non-excited odd, 3 non-excited even.

    Notes
    -----
    With m inputs, consecutive groups of m realisations form one block of
    experiments (their input matrix must be invertible per line); the number
    of realisations must be a multiple of m. With one period per
    realisation the noise variance is unknown (NaN) and ``var_nonlinear`` is
    NaN; with one block, ``var_total`` equals ``var_noise``.
    """
    N = U_periods[0].shape[1]
    m = U_periods[0].shape[2]
    p = Y_periods[0].shape[2]
    R = len(U_periods)
    Uf = [np.fft.rfft(u, axis=1) for u in U_periods]  # (P_r, n_bins, m)
    Yf = [np.fft.rfft(y, axis=1) for y in Y_periods]
    U_mean = np.stack([u.mean(axis=0) for u in Uf])  # (R, n_bins, m)
    Y_mean = np.stack([y.mean(axis=0) for y in Yf])
    if lines is None:
        lines = excited_lines(U_mean, gap_db=DETECTION_GAP_DB)
    lines = np.asarray(lines, dtype=int)
    if lines.size == 0:
        raise ValueError(
            "No excited line found in the input spectrum of X (a constant or zero "
            "input excites nothing); is the input a multisine?"
        )
    if R % m:
        raise ValueError(
            f"With {m} inputs, the number of realisations (signals in X) must be a "
            f"multiple of {m} (one block of {m} experiments per FRF); got {R}."
        )
    n_blocks = R // m
    n_per = np.array([u.shape[0] for u in U_periods])

    frf_blocks = np.empty((n_blocks, lines.size, p, m), dtype=complex)
    var_noise_blocks = np.full((n_blocks, lines.size, p, m), np.nan)
    for b in range(n_blocks):
        sel = slice(b * m, (b + 1) * m)
        Ub = U_mean[sel][:, lines]
        try:
            frf_blocks[b] = _frf_of_block(Ub, Y_mean[sel][:, lines])
        except np.linalg.LinAlgError:
            raise ValueError(
                f"The input X of realisation(s) {list(range(b * m, (b + 1) * m))} has no power (or, "
                "with several inputs, no independent excitation) at some excited line; "
                "pass lines= explicitly or use random-phase multisines as input."
            ) from None
        P = n_per[sel].min()
        if P >= 2:
            # Noise on G: the output's period-to-period spread mapped through
            # the (noiseless) period-averaged input.
            dev = [Yf[r][:P, lines] - Yf[r][:P, lines].mean(axis=0) for r in range(b * m, (b + 1) * m)]
            G_per = np.stack([_frf_of_block(Ub, np.stack([d[i] for d in dev])) for i in range(P)])
            var_noise_blocks[b] = np.sum(np.abs(G_per) ** 2, axis=0) / (P - 1) / P

    frf = frf_blocks.mean(axis=0)
    var_noise = np.mean(var_noise_blocks, axis=0) / n_blocks
    if n_blocks >= 2:
        var_total = np.var(frf_blocks, axis=0, ddof=1) / n_blocks
    else:
        var_total = var_noise.copy()
    var_nonlinear = np.maximum(var_total - var_noise, 0.0)

    n_bins = N // 2 + 1
    output_level = np.mean(np.abs(Y_mean) ** 2, axis=0)  # (n_bins, p)
    noise_level = np.full((n_bins, p), np.nan)
    if n_per.min() >= 2:
        noise_level = np.mean(
            [np.var(y, axis=0, ddof=1) / y.shape[0] for y in Yf], axis=0
        )
    line_kind = np.zeros(n_bins, dtype=int)
    bins = np.arange(n_bins)
    line_kind[1:] = np.where(bins[1:] % 2 == 1, 2, 3)
    line_kind[lines] = 1
    return PeriodicBLA(
        lines=lines,
        frf=frf,
        var_total=var_total,
        var_noise=var_noise,
        var_nonlinear=var_nonlinear,
        n_realizations=R,
        n_periods=int(n_per.min()),
        output_level=output_level,
        noise_level=noise_level,
        line_kind=line_kind,
    )


def welch_bla(U_list, Y_list, nperseg):
    """BLA of non-periodic data by Welch's H1 estimator (Hann windows, 50 %
    overlap), with the coherence-based variance of the estimate.

    Parameters
    ----------
    U_list, Y_list : list of ndarray (n_samples_i, m) / (n_samples_i, p)
    nperseg : int
        Segment length; the frequency grid is ``k / nperseg``.

    Returns
    -------
    lines : ndarray of int, bins 1..nperseg//2 with input power
    frf : ndarray (K, p, m)
    var : ndarray (K, p, m)
    """
    m = U_list[0].shape[1]
    p = Y_list[0].shape[1]
    window = np.hanning(nperseg + 2)[1:-1]
    step = max(nperseg // 2, 1)
    n_bins = nperseg // 2 + 1
    Suu = np.zeros((n_bins, m, m), dtype=complex)
    Syu = np.zeros((n_bins, p, m), dtype=complex)
    Syy = np.zeros((n_bins, p), dtype=float)
    n_seg = 0
    for U, Y in zip(U_list, Y_list):
        for start in range(0, U.shape[0] - nperseg + 1, step):
            Uf = np.fft.rfft((U[start : start + nperseg] - U[start : start + nperseg].mean(0)) * window[:, None], axis=0)
            Yf = np.fft.rfft((Y[start : start + nperseg] - Y[start : start + nperseg].mean(0)) * window[:, None], axis=0)
            Suu += Uf[:, :, None] * Uf[:, None, :].conj()
            Syu += Yf[:, :, None] * Uf[:, None, :].conj()
            Syy += np.abs(Yf) ** 2
            n_seg += 1
    power = np.real(np.einsum("kii->k", Suu))
    lines = np.flatnonzero(power > power.max() * 1e-10)
    lines = lines[lines > 0]
    Suu_l = Suu[lines] + np.eye(m) * 1e-12 * power[lines, None, None]
    frf = np.linalg.solve(Suu_l.transpose(0, 2, 1), Syu[lines].transpose(0, 2, 1)).transpose(0, 2, 1)
    # Residual output power (not explained linearly) sets the FRF variance.
    explained = np.real(np.einsum("kpm,kmq,kpq->kp", frf, Suu_l, frf.conj()))
    residual = np.maximum(Syy[lines] - explained, 0.0)
    inv_uu = np.real(np.einsum("kii->ki", np.linalg.inv(Suu_l)))
    var = residual[:, :, None] * inv_uu[:, None, :] / max(n_seg - m, 1)
    return lines, frf, var
