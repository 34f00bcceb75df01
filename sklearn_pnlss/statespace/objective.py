"""The weighted simulation-error cost that Levenberg-Marquardt minimises.

The cost is the sum over training segments of the squared simulation error,
optionally weighted

- in time: each sample and output by ``Segment.time_weight``;
- in frequency: each DFT bin of each period by ``Segment.freq_weight``
  (zero outside the band of interest). The error of each period is taken to
  the frequency domain with a unitary DFT, interior bins counted twice, so
  that unit weights at all bins give back the time-domain cost (Parseval).

The Jacobian is used through the normal equations J^T J and J^T e,
accumulated segment by segment: only one segment's Jacobian per thread is
ever in memory, whatever the number of signals. Segments can be processed by
several threads: the compiled kernels and the BLAS products release the GIL.
"""
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from ..utils.threads import one_blas_thread, over_column_spans, symmetric_threads_for

__all__ = ["SimulationError", "weigh"]

# Bytes of Jacobian held at once per thread: the rows of a segment are taken
# this many at a time. Large enough that each block's J^T J runs at the BLAS
# rate (F-16, 2,893 parameters: 1,843 samples, 5,529 rows; measured, blocks
# of 2,763 rows took 17 % longer per row than blocks of 11,052), small
# enough that memory does not grow with the signal (a whole 8,192-sample
# F-16 segment was 570 MB).
JACOBIAN_BLOCK_BYTES = 128 * 2**20

# Above this many parameters the Jacobian blocks are held, and the Gram
# matrix J^T J formed, in single precision: J^T J is then the bulk of an
# iteration (rows times parameters squared), and single precision runs
# faster (F-16, 2,893 columns: 1.3 to 1.7 times the double-precision rate
# on 2 cores; a decoupled F-16 model of 525 parameters, two fitted side by
# side on one core each: 66 s in double precision, 44 s in single, test
# NRMSE 0.1684 and 0.1689, benchmarks/bench_side_by_side.py) in half the
# memory. The gradient J^T e is summed in double precision from the same
# rows, and every step is still accepted or rejected on the cost in double
# precision: only the metric of the step is rounded (to 1e-7 of the largest
# column, which the damping dominates), so the fit cannot end worse, and it
# stops where the gradient vanishes as before. Smaller models keep double
# precision throughout: their iterations wait on the recursion and the
# simulations, not on J^T J.
SINGLE_PRECISION_PARAMS = 512


def jacobian_dtype(n_params):
    """The precision the Jacobian blocks of a model of ``n_params``
    parameters are held in (see ``SINGLE_PRECISION_PARAMS``)."""
    return np.float32 if n_params > SINGLE_PRECISION_PARAMS else np.float64


@numba.njit(cache=True, nogil=True)
def _add_gradient_kernel(J, e, g, c0):
    # each row's columns as a view of a contiguous block, indexed by the
    # loop's own variable: numba vectorises that loop (a strided view of
    # the block, J[:, c0:c1], kept it scalar: 2.3 times slower)
    for i in range(J.shape[0]):
        ei = e[i]
        row = J[i, c0 : c0 + g.shape[0]]
        for j in range(row.shape[0]):
            g[j] += row[j] * ei


def _add_gradient(J, e, g):
    """``g += J[:, :len(g)]^T e`` summed in double precision, whatever
    ``J``'s (a Jacobian block, its start-state columns after the first
    ``len(g)``); the columns shared out over the cores BLAS would use (it
    reads the whole Jacobian: 0.2 s of an F-16 iteration on one core)."""
    over_column_spans(lambda c0, c1: _add_gradient_kernel(J, e, g[c0:c1], c0), g.shape[0], 256)


def block_length(seg, n_outputs, n_params, itemsize=8):
    """Samples per Jacobian block of ``seg`` (entries of ``itemsize``
    bytes): whole periods when it is weighted in frequency (each period
    goes through one DFT)."""
    L = max(1, JACOBIAN_BLOCK_BYTES // (itemsize * n_outputs * n_params))
    if seg.freq_weight is not None:
        return -(-L // seg.period) * seg.period
    # Blocks of equal length: a last sliver of a block runs J^T J far
    # below the BLAS rate (F-16: 488 samples after two of 3,852).
    T = seg.Y.shape[0]
    return -(-T // -(-T // L))


def weigh(seg, R, start=0, overwrite=False):
    """Weighted residual rows from R of shape (T, p, k) (k = 1 for the error,
    n_params for its Jacobian), rows ``start:start + T`` of the segment's
    error; returns (n_rows, k), real. With a frequency weight, ``start`` and
    ``T`` are whole periods. ``overwrite``: a time weight may be applied in
    R itself (a Jacobian block's work array: a weighted copy of each block
    cost a quarter of the F-16 normal equations, most of it the first
    touch of the copy's pages)."""
    T, p, k = R.shape
    if seg.time_weight is not None:
        # in R's precision: double weights would promote a single-precision
        # Jacobian to double, doubling its Gram matrix's time and memory
        w = np.sqrt(seg.time_weight[start : start + T]).astype(R.dtype, copy=False)
        weighted = np.multiply(w[:, :, None], R, out=R if overwrite else None)
        return weighted.reshape(-1, k)
    if seg.freq_weight is None:
        return R.reshape(-1, k)
    N = seg.period
    bins = np.flatnonzero(np.any(seg.freq_weight > 0, axis=1))
    # Real and imaginary parts of the unitary DFT; the interior bins stand for
    # their negative-frequency twins too, hence the factor 2 in the weight.
    twice = np.where((bins == 0) | (2 * bins == N), 1.0, 2.0)
    w = np.sqrt(seg.freq_weight[bins] * twice[:, None] / N)[None, :, :, None]
    F = np.fft.rfft(R.reshape(T // N, N, p, k), axis=1)[:, bins] * w
    return np.concatenate([F.real, F.imag], axis=1).reshape(-1, k)


def _key(model):
    """What a model's simulations depend on: its kind, parameters and
    trusted range."""
    bounds = getattr(model, "bounds", None)
    return type(model), model.theta.tobytes(), None if bounds is None else np.asarray(bounds).tobytes()


class SimulationError:
    """Weighted simulation error of a model over training segments.

    Parameters
    ----------
    segments : list of Segment
    n_threads : int, default=1
        Threads over the segments.
    """

    def __init__(self, segments, n_threads=1):
        self.segments = segments
        self.n_threads = max(1, min(int(n_threads), len(segments)))
        # The last residual's simulations (start, error, states):
        # Levenberg-Marquardt asks for the normal equations at the step it
        # has just accepted, whose error the trial simulated already (a
        # simulation per iteration saved; a tenth of the 10-iteration
        # Bouc-Wen fit), and for its trusted range (see trajectory).
        self._simulated = (None, {})

    def _over_chunks(self, function):
        """``function(segments)`` on contiguous chunks of the segments, one
        chunk per thread; the results in segment order."""
        if self.n_threads == 1:
            return [function(self.segments)]
        bounds = np.linspace(0, len(self.segments), self.n_threads + 1).astype(int)
        chunks = [self.segments[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
        # One BLAS thread per segment thread (see one_blas_thread; unthreaded,
        # the 20 Bouc-Wen realisations took 8 s per 10 iterations).
        with one_blas_thread(), ThreadPoolExecutor(self.n_threads) as pool:
            return list(pool.map(function, chunks))

    def residual(self, model):
        """Weighted residual vector, or None when the model diverges."""

        simulated = {}

        def chunk_residuals(segments):
            out = []
            for seg in segments:
                start = model.segment_start(seg)
                run = model.segment_run(seg, start)
                if run is None or not np.all(np.isfinite(run[0])):
                    return None
                err, states = run
                simulated[id(seg)] = start, err, states
                out.append(weigh(seg, err[:, :, None]).ravel())
            return out

        parts = self._over_chunks(chunk_residuals)
        if any(p is None for p in parts):
            return None
        self._simulated = (_key(model), simulated)
        return np.concatenate([e for p in parts for e in p])

    def trajectory(self, model):
        """``model.segments_trajectory`` of the segments, from the last
        residual's simulations when they were of this model: the trusted
        range of each accepted iterate, and the step basis of each stage,
        are read along the trajectory its residual has just simulated (a
        decoupled Bouc-Wen fit with validation simulated its training
        segments a second time per iteration: 12 % of the fit)."""
        key, simulated = self._simulated
        if key == _key(model) and all(id(seg) in simulated for seg in self.segments):
            return np.vstack([np.hstack([simulated[id(seg)][2], seg.U]) for seg in self.segments])
        return model.segments_trajectory(self.segments)

    def normal_equations(self, model):
        """J^T J and J^T e of the weighted residual at ``model``, or None when
        the model diverges."""

        key, simulated = self._simulated
        known = simulated if key == _key(model) else {}

        def chunk_sums(segments, dtype):
            # Accumulated in place: one Gram matrix per thread, not per
            # segment, one Jacobian block at a time. numpy's product (syrk
            # for J^T J) rather than SciPy's BLAS: the eigendecomposition of
            # the step is numpy's too, and two BLAS libraries whose threads
            # wait in turn for work slowed a two-thread fit twofold (Bouc-Wen,
            # degrees 3, 5, 7). A periodic segment's Jacobian is taken in
            # steady state (model.jacobian_blocks): its blocks carry n
            # start-state columns more, folded in at the end (_fold_start_states).
            n_par, n = model.n_params, model.n_states
            G = np.zeros((n_par, n_par))
            products = {}  # J^T J work arrays by size and precision (weights give doubles)

            def work(size, precision):
                if (size, precision) not in products:
                    products[size, precision] = np.empty((size, size), precision)
                return products[size, precision]

            g = np.zeros(n_par)
            buffers = {}  # one work array per column count, for the blocks of all segments
            start_states = []  # per steady segment: what its start state folds in
            for seg in segments:
                if id(seg) in known:
                    start, err, _ = known[id(seg)]
                else:
                    start = model.segment_start(seg)  # read once for the error and its Jacobian
                    err = model.segment_error(seg, start)
                if err is None:
                    return None
                steady = {} if model.steady_state_pays(seg) else None
                n_cols = n_par + (n if steady is not None else 0)
                L = min(block_length(seg, err.shape[1], n_cols, np.dtype(dtype).itemsize), err.shape[0])
                if n_cols not in buffers or buffers[n_cols].shape[0] < L:
                    buffers[n_cols] = np.empty((L, err.shape[1], n_cols), dtype)
                if steady is not None:
                    cross, KK, Ke = np.zeros((n_par, n)), np.zeros((n, n)), np.zeros(n)
                for row, J in model.jacobian_blocks(seg, L, buffer=buffers[n_cols], start=start, steady=steady):
                    e = weigh(seg, err[row : row + J.shape[0], :, None], row)[:, 0]
                    Jw = weigh(seg, J, row, overwrite=True)  # the block is not read again
                    Jp, K = Jw[:, :n_par], Jw[:, n_par:]  # strided views: syrk takes them as they are
                    if Jw.dtype == np.float64:
                        G += np.matmul(Jp.T, Jp, out=work(n_par, Jw.dtype))
                        g += Jp.T @ e
                        if steady is not None:
                            # K^T J transposed, not J^T K: the same products
                            # (the same bits), in 0.28 ms against 0.49 for
                            # a Bouc-Wen segment (one thread, 71 columns)
                            cross += (K.T @ Jp).T
                            KK += K.T @ K
                    else:
                        # The start-state columns ride along in the one
                        # product: a second pass over the block for J^T K
                        # cost 4 % of the iteration (F-16).
                        JJ = np.matmul(Jw.T, Jw, out=work(n_cols, Jw.dtype))
                        G += JJ[:n_par, :n_par]
                        _add_gradient(Jw, e, g)
                        if steady is not None:
                            cross += JJ[:n_par, n_par:]
                            KK += JJ[n_par:, n_par:]
                    if steady is not None:
                        Ke += K.T @ e
                if steady is not None:
                    start_states.append((cross, KK, Ke, steady["S0"]))
            _fold_start_states(G, g, start_states, model.n_state_params)
            return G, g

        def sums(dtype):
            def chunk(segments):
                if dtype == np.float64:
                    return chunk_sums(segments, dtype)
                with np.errstate(over="ignore", invalid="ignore"):  # set in each thread: it is per thread
                    return chunk_sums(segments, dtype)

            parts = self._over_chunks(chunk)
            if any(part is None for part in parts):
                return None
            return sum(G for G, _ in parts), sum(g for _, g in parts)

        dtype = jacobian_dtype(model.n_params)
        with symmetric_threads_for(model.n_params + model.n_states):  # the Gram's order, start states included
            result = sums(dtype)
            if dtype == np.float64 or result is None or all(np.all(np.isfinite(a)) for a in result):
                return result
            # Single precision ends at 3e38: a model far from its data (a
            # start on badly scaled signals) can have sensitivities whose
            # products overflow there and not in double precision; those
            # normal equations are formed again in double precision.
            return sums(np.float64)


def _fold_start_states(G, g, start_states, n_sx):
    """Turn the normal equations of ``J`` into those of ``J + K Z`` for each
    steady segment, given its ``(J'K, K'K, K'e, S0)``: ``K`` is the output's
    sensitivity to the segment's start state, ``Z = [S0, 0]`` that state's
    sensitivity to the parameters (``S0``: (n, n_sx), the first n_sx).

    ``(J + K Z)'(J + K Z) - J'J = JK Z + Z' JK' + Z' KK Z = X Y'`` with
    ``X = [JK, Z']`` and ``Y = [Z', JK + Z' KK]``: a symmetric update of
    rank 2n per segment, all segments in one matrix product.
    """
    if not start_states:
        return
    p = G.shape[0]
    X, Y = [], []
    for cross, KK, Ke, S0 in start_states:
        Zt = np.zeros((p, S0.shape[0]))
        Zt[:n_sx] = S0.T
        X += [cross, Zt]
        Y += [Zt, cross + Zt @ KK]
        g += Zt @ Ke
    G += np.hstack(X) @ np.hstack(Y).T
