"""Training signals turned into simulation segments.

A periodic signal (``period`` set, length a whole number of periods) is in
steady state: the end of its last period is prepended as a transient so that
no sample is lost, and its periods may be averaged first (the noise power
drops by the number of periods; with a steady-state model the least-squares
optimum is unchanged, since the model's output repeats every period). Any
other signal is simulated from rest and its first ``n_skip`` samples may be
left out of the cost, or from the state its first ``init_window`` samples
show (a record that does not start from rest).
"""
import numpy as np

from ..utils.validation import is_periodic
from .model_base import Segment

__all__ = ["transient_length", "average_periods", "make_segments"]


def transient_length(A, period, tol=1e-9):
    """Samples for the slowest linear mode to decay by ``tol``, at least 10
    and at most one period (prepending a whole period is always enough for a
    stable model)."""
    rho = np.max(np.abs(np.linalg.eigvals(A)))
    n = int(np.ceil(np.log(tol) / np.log(rho))) if 0 < rho < 1 else period
    return int(np.clip(n, 10, period))


def average_periods(U, Y, period, weight=None):
    """One period from P steady-state periods.

    With time weights, the target is the weighted mean over periods and the
    weight their sum: sum_p w_p (yhat - y_p)^2 equals
    (sum_p w_p) (yhat - ybar_w)^2 plus a constant, so the optimum is kept.
    """
    P = U.shape[0] // period
    U_p = U.reshape(P, period, -1)
    Y_p = Y.reshape(P, period, -1)
    if weight is None:
        return U_p.mean(axis=0), Y_p.mean(axis=0), None
    W_p = np.broadcast_to(weight, Y.shape).reshape(P, period, -1)
    W_sum = W_p.sum(axis=0)
    safe = np.where(W_sum > 0, W_sum, 1.0)
    return U_p.mean(axis=0), (W_p * Y_p).sum(axis=0) / safe, W_sum


def make_segments(
    X_list, y_list, *, period, n_transient, n_skip=0, average=False,
    time_weights=None, freq_weight=None, init_window=0, pieces=1,
):
    """Segments for :class:`~sklearn_pnlss.statespace.objective.SimulationError`.

    Parameters
    ----------
    X_list, y_list : list of ndarray (n_samples_i, m) / (n_samples_i, p)
    period : int or None
    n_transient : int
        Samples prepended to periodic signals.
    n_skip : int
        Samples left out of the cost at the start of the other signals.
    init_window : int
        Without ``n_skip``: samples at the start of the other signals whose
        outputs set their initial state (at most the signal).
    pieces : int
        With ``init_window``: each of the other signals cut into this many
        consecutive segments (each at least four windows long), every one
        starting from the state its own first samples show, so that
        threads over the segments share a long record.
    average : bool
        Average periodic signals over their periods first.
    time_weights : list of ndarray or None
        Per-sample weights, broadcastable to each ``y``.
    freq_weight : callable (i, n_averaged) -> ndarray or None
        Weights per DFT bin of one period for the periodic segment of
        signal ``i`` whose periods are each the mean of ``n_averaged``
        measured periods.
    """
    segs = []
    for i, (U, Y) in enumerate(zip(X_list, y_list)):
        W = None if time_weights is None else np.broadcast_to(time_weights[i], Y.shape)
        if not is_periodic(U.shape[0], period):
            skip = min(n_skip, U.shape[0] - 1)
            window = 0 if skip else min(init_window, U.shape[0])
            n_pieces = max(1, min(pieces, U.shape[0] // (4 * window))) if window else 1
            cuts = np.linspace(0, U.shape[0], n_pieces + 1).astype(int)
            for a, b in zip(cuts[:-1], cuts[1:]):
                segs.append(Segment(U[a:b], Y[a + skip:b], skip,
                                    time_weight=None if W is None else W[a + skip:b], init_window=window))
            continue
        n_averaged = 1
        if average and U.shape[0] > period:
            n_averaged = U.shape[0] // period
            U, Y, W = average_periods(U, Y, period, W)
        n_tr = min(n_transient, U.shape[0])
        fw = None if freq_weight is None else freq_weight(i, n_averaged)
        segs.append(Segment(
            np.vstack([U[U.shape[0] - n_tr :], U]), Y, n_tr,
            time_weight=None if W is None else np.ascontiguousarray(W),
            freq_weight=fw, period=period,
        ))
    return segs
