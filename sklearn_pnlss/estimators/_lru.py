"""A deep network of linear recurrent units (LRU: Orvieto et al., ICML
2023), fitted by Adam with exact gradients, in numpy: the learned map of
:class:`~sklearn_pnlss.LRUAboveBandRegressor`.

Each layer normalises its input, passes it through ``n_modes`` complex
first-order recursions ``s(t) = lam s(t - 1) + B v(t)`` (stable by
construction: ``|lam| = exp(-exp(nu)) < 1``), reads them out as ``Re(C s)
+ D v``, applies a GELU and a linear mixing, and adds the result to its
input. The recursions are diagonal, so a compiled loop over the samples
costs ``n_modes`` complex products a sample, next to the ``2 n_modes
width`` of the products with ``B`` and ``C``; forward from rest, or in
periodic steady state over one period (the response from rest plus the
free response of the state that the period's end carries into its start,
in closed form), and backward by the adjoint recursion, likewise.

For a complex quantity ``z`` the gradient kept is ``dL/dRe(z) + i
dL/dIm(z)``, so that ``dL = Re(sum conj(grad) dz)``. Internal: may change
without notice.
"""
import math

import numba
import numpy as np
from joblib import Parallel, cpu_count, delayed, effective_n_jobs
from numba import njit, prange

from ..utils.threads import one_blas_thread

__all__ = ["LRUNetwork", "Workspace", "batch_loss", "fit_network", "fit_networks", "one_cycle"]


@njit(parallel=True, cache=True, fastmath=True)
def _recurse(b, lam, n_seq, periodic, adjoint):
    """The recursions ``x[t, n] = lam[n] x[t - 1, n] + b[t, n]``, in place
    of ``b``, of each of ``n_seq`` sequences stacked along the rows of
    ``b`` (n_seq * n_samples, 2 n_modes: the real parts of the modes in the
    first half of the columns, the imaginary in the second): from rest, or
    (``periodic``) in periodic steady state over each sequence (``x[-1] =
    x[T - 1]``: the response from rest plus ``lam^(t + 1) x[-1]``, with
    ``x[-1] = x0[T - 1] / (1 - lam^T)``). With ``adjoint``, the adjoint
    recursion backwards in time, ``g[t] = b[t] + conj(lam) g[t + 1]``,
    likewise. Sample-major, one sequence a job: each step reads and writes
    one row, the modes' updates side by side in the vector units (a job
    taking a part of the modes would stream every row's cache lines for a
    part of each). The states are carried in double precision."""
    n_rows, n_columns = b.shape
    n_modes, n_samples = n_columns // 2, n_rows // n_seq
    l_re, l_im = lam.real.copy(), (-lam.imag if adjoint else lam.imag).copy()
    for k in prange(n_seq):
        s_re, s_im = np.zeros(n_modes), np.zeros(n_modes)
        for i in range(n_samples):
            row = b[k * n_samples + (n_samples - 1 - i if adjoint else i)]
            for n in range(n_modes):
                r = l_re[n] * s_re[n] - l_im[n] * s_im[n] + row[n]
                s_im[n] = l_re[n] * s_im[n] + l_im[n] * s_re[n] + row[n_modes + n]
                s_re[n] = r
                row[n], row[n_modes + n] = r, s_im[n]
        if periodic:
            # what enters before the first sample is the state after the last, in steady state
            for n in range(n_modes):
                lam_n = l_re[n] + 1j * l_im[n]
                carried = lam_n * (s_re[n] + 1j * s_im[n]) / (1.0 - lam_n**n_samples)
                s_re[n], s_im[n] = carried.real, carried.imag
            for i in range(n_samples):
                row = b[k * n_samples + (n_samples - 1 - i if adjoint else i)]
                for n in range(n_modes):
                    row[n] += s_re[n]
                    row[n_modes + n] += s_im[n]
                    r = l_re[n] * s_re[n] - l_im[n] * s_im[n]
                    s_im[n] = l_re[n] * s_im[n] + l_im[n] * s_re[n]
                    s_re[n] = r
    return b


# Abramowitz and Stegun's 7.1.26 for Phi(v) = 1 - 0.5 density(v) t P(t), t = 1 / (1 + A |v|), as single-precision
# constants: a network in single precision computes its activations in it (a third faster than in double)
_A = np.float32(0.3275911 / math.sqrt(2.0))  # the formula's t at |v| / sqrt(2)
_P = tuple(np.float32(c) for c in (0.254829592, -0.284496736, 1.421413741, -1.453152027, 1.061405429))
_HALF, _ONE, _INV_SQRT_2PI = np.float32(0.5), np.float32(1.0), np.float32(1.0 / math.sqrt(2.0 * math.pi))


@njit(parallel=True, cache=True, fastmath=True)
def _gelu(x, out, slope):
    """GELU ``x Phi(x)`` of each element of ``x`` (n_rows, n_columns) and
    its derivative ``Phi(x) + x phi(x)``, written to ``out`` and ``slope``.
    ``Phi`` by Abramowitz and Stegun's 7.1.26 (absolute error below 1.5e-7,
    under float32's resolution), whose one exponential is also ``phi``'s:
    half the cost of ``erf`` and ``exp`` apart."""
    p0, p1, p2, p3, p4 = _P
    for i in prange(x.shape[0]):
        for j in range(x.shape[1]):
            v = x[i, j]
            density = math.exp(-_HALF * v * v)
            t = _ONE / (_ONE + _A * abs(v))
            tail = _HALF * density * t * (p0 + t * (p1 + t * (p2 + t * (p3 + t * p4))))
            cdf = _ONE - tail if v >= 0 else tail
            out[i, j] = v * cdf
            slope[i, j] = cdf + v * density * _INV_SQRT_2PI
    return out, slope


@njit(parallel=True, cache=True, fastmath=True)
def _layer_norm(h, gain, bias, out, normed, inv_std):
    """Each row of ``h`` (n_rows, width) normalised to zero mean and unit
    variance (``normed``), then scaled and shifted (``gain``, ``bias``):
    writes that to ``out``, and ``normed`` and each row's inverse standard
    deviation (``inv_std``)."""
    n_rows, width = h.shape
    for i in prange(n_rows):
        mean = 0.0
        for j in range(width):
            mean += h[i, j]
        mean /= width
        variance = 0.0
        for j in range(width):
            variance += (h[i, j] - mean) ** 2
        inv = 1.0 / math.sqrt(variance / width + 1e-5)
        inv_std[i] = inv
        for j in range(width):
            z = (h[i, j] - mean) * inv
            normed[i, j] = z
            out[i, j] = z * gain[j] + bias[j]
    return out, normed, inv_std


@njit(parallel=True, cache=True, fastmath=True)
def _layer_norm_backward(g_out, normed, inv_std, gain, g_h):
    """Adds to ``g_h`` the gradient with respect to :func:`_layer_norm`'s
    input of a loss whose gradient with respect to its output is
    ``g_out``."""
    n_rows, width = g_out.shape
    for i in prange(n_rows):
        mean_g, mean_gz = 0.0, 0.0
        for j in range(width):
            g_n = g_out[i, j] * gain[j]
            mean_g += g_n
            mean_gz += g_n * normed[i, j]
        mean_g /= width
        mean_gz /= width
        for j in range(width):
            g_h[i, j] += inv_std[i] * (g_out[i, j] * gain[j] - mean_g - normed[i, j] * mean_gz)
    return g_h


@njit(parallel=True, cache=True, fastmath=True)
def _pole_gradient(s, g, n_seq, periodic):
    """``sum_k,t conj(s[k, t - 1, n]) g[k, t, n]`` for each mode ``n``: the
    gradient of ``lam`` from the states ``s`` and the adjoint states ``g``
    (in :func:`_recurse`'s layout; ``s[k, -1]``: the last state in steady
    state, 0 from rest)."""
    n_rows, n_columns = s.shape
    n_modes, n_samples = n_columns // 2, n_rows // n_seq
    total = np.zeros((n_seq, 2, n_modes))
    for k in prange(n_seq):
        for i in range(0 if periodic else 1, n_samples):
            before = s[k * n_samples + (i - 1 if i > 0 else n_samples - 1)]
            now = g[k * n_samples + i]
            for n in range(n_modes):
                total[k, 0, n] += before[n] * now[n] + before[n_modes + n] * now[n_modes + n]
                total[k, 1, n] += before[n] * now[n_modes + n] - before[n_modes + n] * now[n]
    return total[:, 0].sum(axis=0) + 1j * total[:, 1].sum(axis=0)


class LRUNetwork:
    """``n_layers`` residual LRU layers of width ``width`` between a linear
    encoder of ``n_inputs`` channels and a linear decoder to ``n_outputs``.

    ``params`` is a dict of arrays (complex ones for ``B`` and ``C``);
    :meth:`backward` returns the gradients in the same layout. A batch of
    sequences of one length, all periodic or all from rest, goes through
    at once (``x`` of shape (n_sequences, n_samples, n_inputs)): the
    products with the weights as one product each, the sequences'
    recursions shared out over the cores. ``single``: the signals
    and products in float32 (the parameters, their gradients and Adam's
    moments stay float64); False computes in float64 throughout (what a
    finite-difference check needs)."""

    def __init__(self, n_inputs, n_outputs, width, n_layers, n_modes, rng, r_min=0.9, r_max=0.9995,
                 max_phase=0.6 * np.pi, single=True):
        def linear(n_in, n_out):
            bound = 1.0 / np.sqrt(n_in)
            return rng.uniform(-bound, bound, (n_out, n_in)), rng.uniform(-bound, bound, n_out)

        p = {}
        p["enc_W"], p["enc_b"] = linear(n_inputs, width)
        p["dec_W"], p["dec_b"] = linear(width, n_outputs)
        for k in range(n_layers):
            # radii uniform in the ring r_min..r_max (by their squares), phases up to max_phase a sample
            r2 = rng.uniform(r_min**2, r_max**2, n_modes)
            p[f"nu{k}"] = np.log(-0.5 * np.log(r2))
            p[f"theta{k}"] = np.log(rng.uniform(0.0, max_phase, n_modes) + 1e-3)
            p[f"B{k}"] = (rng.standard_normal((n_modes, width)) + 1j * rng.standard_normal((n_modes, width))) \
                / np.sqrt(2 * width)
            p[f"C{k}"] = (rng.standard_normal((width, n_modes)) + 1j * rng.standard_normal((width, n_modes))) \
                / np.sqrt(n_modes)
            p[f"D{k}"] = 0.1 * rng.standard_normal(width)
            p[f"ln_g{k}"], p[f"ln_b{k}"] = np.ones(width), np.zeros(width)
            p[f"mix_W{k}"], p[f"mix_b{k}"] = linear(width, width)
        self.params = p
        self.n_layers = n_layers
        self.real = np.float32 if single else np.float64

    @property
    def n_params(self):
        return int(sum(v.size * (2 if np.iscomplexobj(v) else 1) for v in self.params.values()))

    def eigenvalues(self, k):
        """The recursions' eigenvalues ``lam`` of layer ``k``."""
        p = self.params
        return np.exp(-np.exp(p[f"nu{k}"]) + 1j * np.exp(p[f"theta{k}"]))

    # --- one recursion layer -------------------------------------------------
    def _recursion(self, k, v, n_seq, periodic, work):
        """``Re(C s) + D v`` of the recursions ``s(t) = lam s(t - 1) + B
        v(t)`` of layer ``k`` driven by ``v`` (n_seq * n_samples, width),
        from rest or in periodic steady state; and what the backward pass
        needs. The complex products are real ones on the real and imaginary
        parts side by side (``v`` is real): one product each way."""
        p = self.params
        lam = self.eigenvalues(k)
        gamma = np.sqrt(1.0 - np.abs(lam) ** 2)  # unit gain at every radius
        B = p[f"B{k}"] * gamma[:, None]
        B_parts = np.vstack([B.real, B.imag]).astype(self.real)  # (2 n_modes, width)
        # Re(C s) = C_re s_re - C_im s_im
        C_parts = np.vstack([p[f"C{k}"].real.T, -p[f"C{k}"].imag.T]).astype(self.real)  # (2 n_modes, width)
        n_rows = v.shape[0]
        s = _recurse(np.matmul(v, B_parts.T, out=work.get(f"s{k}", (n_rows, B_parts.shape[0]), self.real)),
                     lam, n_seq, periodic, False)
        out = np.matmul(s, C_parts, out=work.get("r", v.shape, self.real))
        out += np.multiply(p[f"D{k}"].astype(self.real), v, out=work.get("product", v.shape, self.real))
        return out, (v, lam, gamma, B_parts, C_parts, s, n_seq, periodic)

    def _recursion_backward(self, k, g_out, cache, grads, work):
        v, lam, gamma, B_parts, C_parts, s, n_seq, periodic = cache
        n_modes = lam.size
        p = self.params
        product = work.get("product", v.shape, self.real)
        grads[f"D{k}"] = np.sum(np.multiply(g_out, v, out=product), axis=0, dtype=np.float64)
        g_v = np.multiply(g_out, p[f"D{k}"].astype(self.real), out=work.get("g_v", v.shape, self.real))
        # Re(C s): dL/dC = g conj(s), dL/ds = conj(C)^T g (gradients as dRe + i dIm)
        G_C = (g_out.T @ s).astype(np.float64)
        grads[f"C{k}"] = G_C[:, :n_modes] - 1j * G_C[:, n_modes:]
        G = _recurse(np.matmul(g_out, C_parts.T, out=work.get("G", s.shape, self.real)), lam, n_seq, periodic,
                     True)  # through the recursion
        G_lam = _pole_gradient(s, G, n_seq, periodic)
        G_B = (G.T @ v).astype(np.float64)
        G_B = G_B[:n_modes] + 1j * G_B[n_modes:]
        g_v += np.matmul(G, B_parts, out=product)
        grads[f"B{k}"] = G_B * gamma[:, None]
        g_gamma = np.real(np.sum(np.conj(G_B) * p[f"B{k}"], axis=1))
        # lam = exp(z), z = -exp(nu) + i exp(theta); gamma = sqrt(1 - exp(-2 exp(nu)))
        G_z = np.conj(lam) * G_lam
        e_nu, e_theta = np.exp(p[f"nu{k}"]), np.exp(p[f"theta{k}"])
        grads[f"nu{k}"] = -e_nu * np.real(G_z) + g_gamma * e_nu * np.abs(lam) ** 2 / gamma
        grads[f"theta{k}"] = e_theta * np.imag(G_z)
        return g_v

    # --- the network -----------------------------------------------------------
    def forward(self, x, periodic, keep=False, work=None):
        """The network's output (n_samples, n_outputs) for ``x`` (n_samples,
        n_inputs), or for a batch (n_sequences, n_samples, n_inputs): from
        rest, or in periodic steady state over each sequence (one period).
        ``work``: a :class:`Workspace` whose arrays the intermediate
        signals are written to (a fit passes the same one at every
        iteration), or None for new arrays."""
        work = _NEW_ARRAYS if work is None else work
        p = {k: v.astype(self.real) for k, v in self.params.items() if not np.iscomplexobj(v)}
        shape = x.shape
        n_seq = 1 if x.ndim == 2 else shape[0]
        x = x.reshape(-1, shape[-1]).astype(self.real)
        n_rows, width = x.shape[0], p["enc_b"].size
        caches = []
        h = np.matmul(x, p["enc_W"].T, out=work.get("h", (n_rows, width), self.real))
        h += p["enc_b"]
        for k in range(self.n_layers):
            # what the backward pass reads is written to arrays of this layer's own
            v, normed, inv_std = _layer_norm(h, p[f"ln_g{k}"], p[f"ln_b{k}"], *work.get_many(
                (f"v{k}", h.shape), (f"normed{k}", h.shape), (f"inv_std{k}", (n_rows,)), dtype=self.real))
            r, rec_cache = self._recursion(k, v, n_seq, periodic, work)
            a, da = _gelu(r, *work.get_many((f"a{k}", r.shape), (f"da{k}", r.shape), dtype=self.real))
            h += np.matmul(a, p[f"mix_W{k}"].T, out=work.get("product", h.shape, self.real))
            h += p[f"mix_b{k}"]
            if keep:
                caches.append((normed, inv_std, rec_cache, a, da))
        if keep:
            self._cache = (x, h, caches, p, shape)
        out = h @ p["dec_W"].T + p["dec_b"]
        return out.reshape(*shape[:-1], out.shape[-1])

    def backward(self, g_out, work=None):
        """The gradients of a loss whose gradient with respect to the last
        :meth:`forward` (with ``keep=True``)'s output is ``g_out``
        (``work``: the workspace that forward was given)."""
        work = _NEW_ARRAYS if work is None else work
        x, h, caches, p, shape = self._cache
        grads = {}
        g_out = g_out.reshape(-1, g_out.shape[-1]).astype(self.real)
        grads["dec_W"], grads["dec_b"] = g_out.T @ h, g_out.sum(axis=0)
        g_h = np.matmul(g_out, p["dec_W"], out=work.get("g_h", h.shape, self.real))
        for k in reversed(range(self.n_layers)):
            normed, inv_std, rec_cache, a, da = caches[k]
            grads[f"mix_W{k}"], grads[f"mix_b{k}"] = g_h.T @ a, g_h.sum(axis=0)
            g_r = np.matmul(g_h, p[f"mix_W{k}"], out=work.get("g_r", h.shape, self.real))
            g_r *= da
            g_v = self._recursion_backward(k, g_r, rec_cache, grads, work)
            grads[f"ln_g{k}"], grads[f"ln_b{k}"] = np.einsum("ij,ij->j", g_v, normed), g_v.sum(axis=0)
            g_h = _layer_norm_backward(g_v, normed, inv_std, p[f"ln_g{k}"], g_h)
        grads["enc_W"], grads["enc_b"] = g_h.T @ x, g_h.sum(axis=0)
        self._cache = None
        return {k: np.asarray(g, dtype=self.params[k].dtype) for k, g in grads.items()}


class Workspace:
    """The arrays of a network's intermediate signals, kept from one
    iteration to the next by name and shape. Each new array costs the
    operating system's zeroing of its pages when first written: on the
    F-16's batch (98,304 rows) a fifth of an iteration, spent again at every
    iteration when the arrays are new ones."""

    def __init__(self):
        self._arrays = {}

    def get(self, name, shape, dtype):
        key = (name, tuple(shape), np.dtype(dtype))
        if key not in self._arrays:
            self._arrays[key] = np.empty(shape, dtype)
        return self._arrays[key]

    def get_many(self, *named_shapes, dtype):
        return [self.get(name, shape, dtype) for name, shape in named_shapes]


class _NewArrays(Workspace):
    """A workspace that gives a new array at every call."""

    def get(self, name, shape, dtype):
        return np.empty(shape, dtype)


_NEW_ARRAYS = _NewArrays()


class _Adam:
    """Adam on the network's parameters (complex ones as their real and
    imaginary parts), its step size and first moment set per iteration."""

    def __init__(self, params, beta2=0.999, eps=1e-8):
        self.beta2, self.eps, self.t = beta2, eps, 0
        self.m = {k: np.zeros(_real(v).shape) for k, v in params.items()}
        self.v = {k: np.zeros(_real(v).shape) for k, v in params.items()}

    def step(self, params, grads, lr, beta1):
        self.t += 1
        for k, p in params.items():
            g, m, v = _real(grads[k]), self.m[k], self.v[k]
            m *= beta1
            m += (1 - beta1) * g
            v *= self.beta2
            v += (1 - self.beta2) * g * g
            m_hat = m / (1 - beta1**self.t)
            v_hat = v / (1 - self.beta2**self.t)
            _real(p)[...] -= lr * m_hat / (np.sqrt(v_hat) + self.eps)


def _real(a):
    """A real view of an array (a complex one's real and imaginary parts
    side by side)."""
    return a.view(np.float64) if np.iscomplexobj(a) else a


def one_cycle(n_iter, max_lr, warm_fraction=0.1, div=25.0, final_div=1e4, beta1_range=(0.85, 0.95)):
    """The step size and Adam's first-moment factor at each iteration of a
    one-cycle schedule (Smith and Topin 2019): the step rises from
    ``max_lr / div`` to ``max_lr`` over the first ``warm_fraction`` of the
    iterations while the momentum falls, then both return on a cosine, the
    step to ``max_lr / (div * final_div)``."""
    warm = max(1, int(round(warm_fraction * n_iter)))
    lo, hi = beta1_range
    for i in range(n_iter):
        if i < warm:
            frac = i / warm
            lr_a, lr_b, b_a, b_b = max_lr / div, max_lr, hi, lo
        else:
            frac = (i - warm) / max(1, n_iter - 1 - warm)
            lr_a, lr_b, b_a, b_b = max_lr, max_lr / (div * final_div), lo, hi
        cos = 0.5 * (1 + np.cos(np.pi * frac))
        yield lr_b + (lr_a - lr_b) * cos, b_b + (b_a - b_b) * cos


def batch_loss(error, weights, floor):
    """The loss of a batch's ``error`` (n_pieces, n_samples, n_outputs)
    summed over its pieces and outputs, and its gradient: with ``e2`` the
    sum over time of ``weights * error**2`` (n_pieces, n_outputs), the sum
    of ``sqrt(floor + e2)``, or of ``e2`` when ``floor`` is None."""
    e2 = np.sum(weights * error**2, axis=1)
    if floor is None:
        return float(np.sum(e2)), 2.0 * weights * error
    root = np.sqrt(np.maximum(floor + e2, np.finfo(float).tiny))
    return float(np.sum(root)), weights * error / root[:, None, :]


def fit_network(network, signals, n_iter, learning_rate, segment_length, burn_in, rng, project=None, clip=1.0):
    """Fit ``network`` by Adam on ``signals``, each a tuple ``(inputs,
    target, weights, periodic, floor)``. The error of each output on a
    signal, ``e2 = mean over time of weights * error**2``, adds to the
    error ``floor`` the network does not model there (e.g. what the model
    leaves in the band: the two are orthogonal, their powers add), and the
    loss is the mean over the signals and outputs of ``sqrt(floor + e2)``:
    with ``weights`` the output's inverse power, the mean NRMSE of the
    whole simulation, as a benchmark scores it. Its gradient weighs each
    output by ``1 / sqrt(floor + e2)``: the outputs and signals simulated
    best count most, where the squared error (``floor`` None: the loss is
    the mean of ``e2``) would let the worst-simulated ones take the
    network. A periodic signal (one period in steady state) is taken
    whole at every iteration; one from rest, a random segment of
    ``segment_length`` samples simulated from rest, its first ``burn_in``
    samples not scored (a segment from the middle of a record starts from
    a state it does not know) unless it starts the record. The pieces of
    one length and kind go through the network as one batch.
    ``project(out, periodic)``: a self-adjoint linear map along the
    samples of each output (n_samples, n_outputs), applied to the
    network's output before the error (what of it the model keeps), or
    None. Returns the loss at each iteration."""
    adam = _Adam(network.params)
    work = Workspace()
    losses = []
    with_floor = signals[0][4] is not None
    n_terms = len(signals) * signals[0][1].shape[1]
    for lr, beta1 in one_cycle(n_iter, learning_rate):
        batches = {}
        for inputs, target, weights, periodic, floor in signals:
            n = inputs.shape[0]
            start, stop, skip = 0, n, 0
            if not periodic and n > segment_length:
                start = int(rng.integers(0, n - segment_length + 1))
                stop, skip = start + segment_length, (0 if start == 0 else min(burn_in, segment_length // 2))
            scored = np.ones((stop - start, 1))
            scored[:skip] = 0.0
            piece = (inputs[start:stop], target[start:stop], weights * scored / np.sum(scored),
                     floor if with_floor else np.zeros(target.shape[1]))
            batches.setdefault((periodic, stop - start), []).append(piece)
        total, grads = 0.0, None
        for (periodic, _), pieces in batches.items():
            inputs, target, weights, floor = (np.stack(part) for part in zip(*pieces))
            out = network.forward(inputs, periodic, keep=True, work=work)
            if project is not None:
                out = np.stack([project(o, periodic) for o in out])
            loss, g = batch_loss(out - target, weights, floor if with_floor else None)
            total += loss / n_terms
            g /= n_terms
            if project is not None:
                g = np.stack([project(piece, periodic) for piece in g])
            g = network.backward(g, work)
            grads = g if grads is None else {k: grads[k] + g[k] for k in g}
        norm = np.sqrt(sum(float(np.sum(_real(g) ** 2)) for g in grads.values()))
        if norm > clip:
            grads = {k: g * (clip / norm) for k, g in grads.items()}
        adam.step(network.params, grads, lr, beta1)
        losses.append(total)
    return np.array(losses)


def fit_networks(settings, signals, training, seeds, project, n_jobs=None):
    """One network ``LRUNetwork(*settings, rng)`` fitted by
    :func:`fit_network` (``signals``, ``training`` = (n_iter,
    learning_rate, segment_length, burn_in), ``project``) for each pair of
    ``seeds`` (its initial weights', its segments'), ``n_jobs`` at a time,
    each in a process of its own with its share of the cores. Returns the
    (network, losses) pairs in the order of ``seeds``."""
    n_workers = min(effective_n_jobs(n_jobs), len(seeds))
    if n_workers == 1:
        # here, every core for the compiled kernels, BLAS on one: its products are too small to share
        # out, and its threads spinning between them take the kernels' cores (0.48 s an iteration on
        # the F-16 on 2 cores, 0.69 s with BLAS on both, measured before the workspace)
        with one_blas_thread():
            return [_fit_one(settings, signals, training, pair, project) for pair in seeds]
    threads = max(1, cpu_count() // n_workers)
    return Parallel(n_jobs=n_workers)(delayed(_fit_one)(settings, signals, training, pair, project, threads)
                                      for pair in seeds)


def _fit_one(settings, signals, training, seeds, project, threads=None):
    if threads is not None:  # a worker: the compiled kernels' threads too (joblib limits BLAS's)
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    network = LRUNetwork(*settings, np.random.default_rng(seeds[0]))
    losses = fit_network(network, signals, *training, np.random.default_rng(seeds[1]), project)
    return network, losses
