"""A one-hidden-layer network on a sliding window of signals: the nonlinear
map of :class:`~sklearn_pnlss.AboveBandRegressor` (``hidden_units``).

The FIR of the linear map sums the gated input's delays; an impact's
ringing, though, depends on how hard and in which phase of the motion the
joint knocks, which no sum of delays holds. The network reads a window of
the model's in-band prediction and the gated input (every ``stride``-th
sample of the last ``n_taps``; with ``in_band``, the input in the band too)
and gives the error above the cutoff (with ``in_band``, all of it) at the
window's newest sample: ``W2 relu(W1 window + b1) + b2``, fitted by
scikit-learn's :class:`~sklearn.neural_network.MLPRegressor`; several such
networks from different starts are averaged. Internal: may change without
notice.
"""
from numbers import Integral

import numpy as np
from joblib import Parallel, delayed, effective_n_jobs
from sklearn.neural_network import MLPRegressor
from sklearn.utils import check_random_state

from ._gated import lagged

__all__ = ["apply_networks", "fit_networks", "held_out_rows", "windows"]

# Adam's settings: mini-batches of 256 windows; at most 150 passes, stopped
# when the held-out windows (``held_out_rows``) have not improved by TOL for
# PATIENCE passes. On the F-16's 262144 training windows their error grows
# from the second pass on (the one waveform of the training levels is being
# learnt by heart), so a fit takes 11 passes, 15 s on 2 cores.
BATCH_SIZE = 256
MAX_PASSES = 150
PATIENCE = 10
TOL = 1e-4


def windows(channels, n_taps, stride, periodic):
    """The network's inputs along one signal (n_samples, n_channels): row
    ``t`` holds every channel at ``t, t - stride, ...`` back to ``n_taps - 1``
    samples (circularly for a periodic signal, else from rest), in single
    precision (the inputs of the whole training set are held at once)."""
    delays = lagged(channels, n_taps, periodic)[:, :, ::stride]
    return delays.reshape(channels.shape[0], -1).astype(np.float32)


def fit_networks(inputs, errors, weights, held_out, hidden_units, alpha, n_networks, random_state, n_jobs=None):
    """``n_networks`` networks fitted on each signal's windows (``inputs``,
    from :func:`windows`) against the error it models (``errors``), each signal's
    rows weighted by ``weights``, from different initial weights (an int
    ``random_state`` seeds the k-th with ``random_state + k``; otherwise
    each gets a seed drawn from it here), ``n_jobs`` of them at a time.
    Returns them and the scales of their inputs (per column) and outputs
    (per output): they work in those units."""
    A = np.vstack(inputs)
    target = np.vstack(errors)
    input_scale = A.std(axis=0)
    input_scale[input_scale == 0] = 1.0
    target_scale = np.sqrt(np.mean(target**2, axis=0))
    target_scale[target_scale == 0] = 1.0
    A /= input_scale
    rows = np.concatenate([np.full(a.shape[0], w) for a, w in zip(inputs, weights)])
    scaled = (target / target_scale).astype(np.float32)
    scaled = scaled[:, 0] if scaled.shape[1] == 1 else scaled
    if isinstance(random_state, Integral):
        seeds = [random_state + k for k in range(n_networks)]
    else:
        # drawn here, not in the workers: each would get its own copy of a
        # generator and draw the same initial weights
        rng = check_random_state(random_state)
        seeds = [int(rng.randint(np.iinfo(np.int32).max)) for _ in range(n_networks)]
    # split once for all the networks (the training windows are the bulk of the memory)
    held_out = np.concatenate(held_out)
    weight = rows / rows.mean()
    fit_part = A[~held_out], scaled[~held_out], weight[~held_out]
    held_out_part = A[held_out], scaled[held_out], weight[held_out]
    # one network alone is fitted here, with every core for its products
    networks = Parallel(n_jobs=min(effective_n_jobs(n_jobs), n_networks))(
        delayed(_fit_network)(fit_part, held_out_part, hidden_units, alpha, seed) for seed in seeds)
    return networks, input_scale, target_scale


def held_out_rows(n_samples, period):
    """The windows that stop the fit: the last tenth of every period (of
    the signal when it is not periodic), one contiguous block. A random
    tenth would not do: the window at ``t`` is nearly the one at ``t - 1``,
    so its score would follow the training score; and the periods of a
    periodic signal repeat one input, so a whole held-out period would too."""
    length = period or n_samples
    return np.arange(n_samples) % length >= length - max(1, length // 10)


def _fit_network(fit_part, held_out_part, hidden_units, alpha, seed):
    """Adam passes over the windows ``fit_part`` (windows, targets,
    weights), the weights kept from the pass best on ``held_out_part``,
    stopped after ``PATIENCE`` passes without a gain."""
    network = MLPRegressor(hidden_layer_sizes=(hidden_units,), alpha=alpha, batch_size=BATCH_SIZE,
                           random_state=seed)
    A_fit, target_fit, weight_fit = fit_part
    A_val, target_val, weight_val = held_out_part
    best, best_loss, stale = None, np.inf, 0
    for _ in range(MAX_PASSES):
        network.partial_fit(A_fit, target_fit, sample_weight=weight_fit)
        miss = (network.predict(A_val) - target_val).reshape(len(A_val), -1)
        loss = float(np.average(np.sum(miss**2, axis=1), weights=weight_val))
        if loss < best_loss * (1 - TOL):
            best_loss, stale = loss, 0
            best = ([w.copy() for w in network.coefs_], [b.copy() for b in network.intercepts_])
        else:
            stale += 1
            if stale >= PATIENCE:
                break
    if best is not None:  # else no pass gave a finite held-out error: the last weights stay
        network.coefs_, network.intercepts_ = best
    return network


def apply_networks(networks, input_scale, target_scale, window_rows):
    """The networks' mean output (n_samples, n_outputs) on one signal's
    windows: their errors, from different starts, partly cancel."""
    A = window_rows / input_scale
    out = np.mean([network.predict(A).reshape(window_rows.shape[0], -1) for network in networks], axis=0)
    return out.astype(float) * target_scale
