"""A signal's content above a cutoff, switched on by a gate, through FIR
filters, and the hinges of a motion past its clearances: the pieces of
:class:`~sklearn_pnlss.AboveBandRegressor`.

The response is ``sum_j h_j g(t - j) u_above(t - j)``: ``u_above`` the input's
content above the cutoff, ``g = max(F c, 0)`` a gate whose features ``F``
(of the state) are fitted by least squares to the amplitude envelope of
the error above the cutoff, and the ``h_j`` by ridge regression on that
error. Internal: may change without notice.
"""
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import fft as sfft
from scipy import linalg

from ..utils.threads import symmetric_threads_for

__all__ = ["FirRidge", "above_cutoff", "apply_fir", "channel_rms", "envelope", "fit_fir", "fit_gate", "gate", "hinges",
           "integral_in_band", "lagged", "relative_motions"]

# Rows of the gate's features held at once (8192 x 172 for 18 states: 11 MB).
ROWS_PER_BLOCK = 8192


def above_cutoff(signal, cutoff, fs, n_fft=None):
    """The content of each channel of one (n_samples, n_channels) signal
    strictly above ``cutoff`` (zero phase: the DFT of the whole record with
    the lines at and below ``cutoff`` set to zero). ``n_fft``: the
    transform's length, the record padded with zeros to it (its own
    length by default: circularly)."""
    n = signal.shape[0] if n_fft is None else n_fft
    spectrum = sfft.rfft(signal, n, axis=0, workers=-1)
    spectrum[sfft.rfftfreq(n, 1.0 / fs) <= cutoff] = 0.0
    return sfft.irfft(spectrum, n, axis=0, workers=-1)[: signal.shape[0]]


def channel_rms(signals):
    """The rms of each channel over (n_samples, n_channels) signals taken
    together, 1 where it is zero (a scale to divide by)."""
    scale = np.sqrt(np.mean(np.vstack(signals) ** 2, axis=0))
    scale[scale == 0] = 1.0
    return scale


def integral_in_band(signal, low, high, fs, n_integrations):
    """Each channel's content in ``(low, high]``, integrated ``n_integrations``
    times in time (zero phase: divided by ``(2 pi i f)**n`` on the DFT of
    the whole record). The lines at and below ``low`` are dropped, as
    integration would magnify their drift."""
    spectrum = sfft.rfft(signal, axis=0, workers=-1)
    f = sfft.rfftfreq(signal.shape[0], 1.0 / fs)
    keep = (f > low) & (f <= high)
    spectrum[~keep] = 0.0
    spectrum[keep] /= (2j * np.pi * f[keep, None]) ** n_integrations
    return sfft.irfft(spectrum, signal.shape[0], axis=0, workers=-1)


def relative_motions(motion):
    """Each channel of an (n_samples, n) motion and each difference of two
    (``i`` minus ``j``, ``i > j``): where a joint lies between two sensors,
    its motion is their difference."""
    i, j = np.tril_indices(motion.shape[1], -1)
    return np.hstack([motion, motion[:, i] - motion[:, j]])


def hinges(motion, scale, clearances):
    """``max(m - c, 0)`` and ``min(m + c, 0)`` of each channel ``m`` of
    ``motion / scale``, for each clearance ``c``: a contact that opens
    beyond a clearance, in each direction."""
    m = motion / scale
    return np.hstack([h for c in clearances for h in (np.maximum(m - c, 0.0), np.minimum(m + c, 0.0))])


def lagged(w, n_taps, periodic):
    """The delays of one (n_samples, n_channels) signal, as a read-only view
    of shape (n_samples, n_channels, n_taps): ``[t, i, j]`` is channel ``i``
    at ``t - j`` (circularly for a periodic signal in steady state, else
    from rest). Its rows reshaped to ``n_channels * n_taps`` columns are the
    FIR design matrix."""
    n, m = w.shape
    if periodic:
        head = np.take(w, np.arange(-(n_taps - 1), 0), axis=0, mode="wrap")
    else:
        head = np.zeros((n_taps - 1, m))
    return sliding_window_view(np.vstack([head, w]), n_taps, axis=0)[:, :, ::-1]


def _row_blocks(n):
    for start in range(0, n, ROWS_PER_BLOCK):
        yield slice(start, min(start + ROWS_PER_BLOCK, n))


def envelope(error, scale, window, periodic):
    """Where an (n_samples, n_outputs) error above the cutoff lies in time,
    as an amplitude (what a gate on the input scales): the square root of
    its power summed over the outputs, each in units of ``scale``, averaged
    over ``window`` samples (centred; circularly for a periodic signal)."""
    power = np.sum((error / np.where(scale > 0, scale, 1.0)) ** 2, axis=1)
    kernel = np.ones(window) / window
    if not periodic:
        return np.sqrt(np.convolve(power, kernel, mode="same"))
    half = window // 2
    wrapped = np.concatenate([power[power.size - half:], power, power[:window - 1 - half]])
    return np.sqrt(np.convolve(wrapped, kernel, mode="valid"))


def fit_gate(variables, envelopes, features):
    """The gate's coefficients: ``features(v)`` of each signal's variables
    ``v`` (n_samples, n) fitted to its envelope by pooled least squares."""
    normal, rhs = 0.0, 0.0
    for v, e in zip(variables, envelopes):
        for rows in _row_blocks(v.shape[0]):
            F = features(v[rows])
            normal = normal + F.T @ F
            rhs = rhs + F.T @ e[rows]
    return np.linalg.lstsq(normal, rhs, rcond=None)[0]


def gate(x, coef):
    """The gate ``max(q(x), 0)`` along one signal ``x`` (n_samples, n), ``q``
    the quadratic form whose coefficients ``coef`` multiply ``[1, x_i x_j
    (i <= j)]`` (:func:`numpy.triu_indices`' order), evaluated as ``x^T Q
    x``: ``n^2`` flops a sample where the features take ``n^2 / 2`` numbers
    of memory each."""
    n = x.shape[1]
    form = np.zeros((n, n))
    form[np.triu_indices(n)] = coef[1:]
    return np.maximum(coef[0] + np.einsum("ti,ti->t", x @ form, x), 0.0)


def _spectra(w, n_taps, periodic):
    """The rfft of each column of ``w`` and its length: the signal's own
    (circular correlations for a periodic signal in steady state), or padded
    by ``n_taps`` so that the circular ones equal the linear ones at every
    delay of the filters (from rest)."""
    n = w.shape[0] if periodic else sfft.next_fast_len(w.shape[0] + n_taps, real=True)
    return sfft.rfft(w, n, axis=0, workers=-1), n


def _correlations(signals, n, n_taps):
    """What the delay designs ``A`` of signals of one transform length give
    the normal equations, summed over them, from the spectra rather than
    ``A``: ``corr[i, j, d + n_taps - 1] = sum_s w_i(s) w_j(s + d)`` for ``|d|
    < n_taps`` (``A^T A``'s block ``i, j`` is ``corr[i, j]`` at ``a - b``)
    and ``cross[i, a, k] = sum_t w_i(t - a) r_k(t)`` (``A^T r``).
    ``signals``: ``(spectrum of w, spectrum of the error r)`` of each signal,
    at the transform length ``n``. Correlations add up over signals, so do their
    spectra: one inverse transform for all of them (the estimation levels
    of a benchmark share their length)."""
    m = signals[0][0].shape[1]
    lags = np.r_[n - (n_taps - 1):n, 0:n_taps]  # delays -(n_taps - 1) .. n_taps - 1
    corr = np.empty((m, m, lags.size))
    for i in range(m):  # c_ji(d) = c_ij(-d): the pairs j >= i only
        products = sum(np.conj(W[:, i:i + 1]) * W[:, i:] for W, _ in signals)
        corr[i, i:] = sfft.irfft(products, n, axis=0, workers=-1)[lags].T
        corr[i:, i] = corr[i, i:, ::-1]
    products = sum(np.conj(W)[:, :, None] * R[:, None, :] for W, R in signals)
    cross = sfft.irfft(products, n, axis=0, workers=-1)
    return corr, cross[:n_taps].transpose(1, 0, 2)


def _subtract_past_end(blocks, tails):
    """Take from the normal matrix ``blocks`` (its ``i, a, j, b`` entry at
    ``[i, a, j, b]``) the products past the records' ends: ``sum_{u=1}^{min(a,
    b)} z_i(a - u) z_j(b - u)`` for each record's tail ``z`` (``tails``: one
    (n_taps - 1, n_channels) array a record). Along a diagonal each entry is
    the one before it plus ``z_i(a - 1) z_j(b - 1)``, a recursion of
    ``n_channels^2 n_taps^2`` operations where the product of the tails'
    delay rows takes ``n_taps`` times more (and OpenBLAS's threaded product
    of a matrix with itself crashes at the orders many clearances reach)."""
    m, n_taps = blocks.shape[0], blocks.shape[1]
    later = tails[:, :n_taps - 1, :].reshape(tails.shape[0], -1)  # (records, b * m + j)
    running = np.zeros((m, m, n_taps))  # [i, j, b]: the sum at the current a
    for a in range(1, n_taps):
        step = (tails[:, a - 1, :].T @ later).reshape(m, n_taps - 1, m).transpose(0, 2, 1)
        running[:, :, 1:] = running[:, :, :-1] + step
        blocks[:, a, :, :] -= running


class FirRidge:
    """The ridge regression of FIR filters (n_inputs, n_taps, n_outputs) of
    each signal's error on its gated input's delays, over all the signals
    or any of the ``subsets`` named at construction (cross-validation), at
    any penalty: ``alpha`` relative to the normal matrix's mean diagonal.

    The normal matrix is built from the channels' correlations in
    ``O(n_channels^2 n log n)``, never from the design matrix's ``O(n
    (n_channels n_taps)^2)``: summed over the signals (as spectra: the
    signals of one transform length that every subset takes or leaves
    alike share one inverse transform), laid out block-Toeplitz, less the
    products past each record's end. The correlations are computed once;
    each fit of a subset or a penalty is one sum of them and one Cholesky
    solve."""

    def __init__(self, gated, errors, periodic, n_taps, subsets=()):
        self.n_taps = n_taps
        self.n_inputs, self.n_outputs = gated[0].shape[1], errors[0].shape[1]
        # a signal's membership: in which subsets it is
        subsets = [set(subset) for subset in subsets]
        membership = [tuple(i in subset for subset in subsets) for i in range(len(gated))]
        by_key = {}
        for w, r, p, member in zip(gated, errors, periodic, membership):
            W, n = _spectra(w, n_taps, p)
            by_key.setdefault((n, member), []).append((W, sfft.rfft(r, n, axis=0, workers=-1)))
        self._parts = [(member, *_correlations(signals, n, n_taps)) for (n, member), signals in by_key.items()]
        # from rest, the records' last n_taps - 1 samples read backwards: the correlations hold their products
        # past the record's end, the delay design does not
        self._tails = [(member, w[::-1][:n_taps - 1].copy())
                       for w, p, member in zip(gated, periodic, membership) if not p]

    def solve(self, alpha, subset=None):
        """The filters fitted on every signal, or on subset number
        ``subset`` of those named at construction."""
        def taken(member):
            return subset is None or member[subset]

        m, n_taps = self.n_inputs, self.n_taps
        corr = sum(c for member, c, _ in self._parts if taken(member))
        rhs = sum(x for member, _, x in self._parts if taken(member))
        tails = [tail for member, tail in self._tails if taken(member)]
        # block (i, j) at (a, b) is corr[i, j] at a - b: the windows of the delays read backwards
        windows = sliding_window_view(corr[:, :, ::-1], n_taps, axis=2)[:, :, ::-1]  # (i, j, a, b)
        normal = np.empty((m * n_taps, m * n_taps))
        blocks = normal.reshape(m, n_taps, m, n_taps)
        blocks[...] = windows.transpose(0, 2, 1, 3)
        if tails:
            _subtract_past_end(blocks, np.stack(tails))
        rhs = rhs.reshape(m * n_taps, self.n_outputs)
        scale = np.trace(normal) / normal.shape[0]
        if scale <= 0:  # nothing gated through: nothing to fit
            coef = np.zeros_like(rhs)
        else:
            normal[np.diag_indices(normal.shape[0])] += alpha * scale
            with symmetric_threads_for(normal.shape[0]):
                coef = linalg.solve(normal, rhs, assume_a="pos", overwrite_a=True, check_finite=False)
        return coef.reshape(m, n_taps, self.n_outputs)


def fit_fir(gated, errors, periodic, n_taps, alpha):
    """FIR filters (n_inputs, n_taps, n_outputs) by ridge regression of each
    signal's error on its gated input's delays, over all the signals (see
    :class:`FirRidge`)."""
    return FirRidge(gated, errors, periodic, n_taps).solve(alpha)


def apply_fir(w, fir, periodic):
    """The FIR filters' output (n_samples, n_outputs) on one gated input (by
    the spectra: circularly for a periodic signal, else from rest)."""
    W, n = _spectra(w, fir.shape[1], periodic)
    H = sfft.rfft(fir, n, axis=1)
    return sfft.irfft(np.einsum("fm,mfk->fk", W, H), n, axis=0)[:w.shape[0]]
