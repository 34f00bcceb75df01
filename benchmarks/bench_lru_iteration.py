"""Where an iteration of ``LRUAboveBandRegressor``'s network goes, on the
F-16's training batch, against what its arithmetic needs (issue 35).

    python benchmarks/bench_lru_iteration.py [--iterations 20] [--output FILE]

The network at the class's defaults (three residual layers of 64
recursions, 32 channels, 7 inputs, 3 outputs) on the batch of an F-16
iteration: the four estimation levels' multisine periods (8192 samples
each, in periodic steady state) and a segment of 16384 samples of each of
their sine sweeps (from rest), 98304 samples in all. The values are random:
the time does not depend on them. Measured:

- the products with the weights, the bulk of the arithmetic (``24 n_modes
  width + 6 width**2`` flops a sample and layer, forward and back), timed
  alone at the batch's shapes on one BLAS thread: the time they need at
  the machine's own single-precision rate;
- an iteration of ``fit_network`` (Adam's step, the projection above the
  band, the loss) in this process, the compiled kernels on every core and
  BLAS on one (``fit_networks`` with one network);
- two networks fitted side by side (``fit_networks``, ``n_jobs=2``: a
  process and a core each), the time of an iteration of the pair.

Writes ``results/lru_iteration.json``.
"""
import argparse
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_utils import RESULTS, header, write_results  # noqa: E402

N_INPUTS, N_OUTPUTS, WIDTH, N_LAYERS, N_MODES = 7, 3, 32, 3, 64
PERIOD, SEGMENT, N_LEVELS = 8192, 16384, 4


def training_batch(rng):
    """The signals of an F-16 iteration, as ``fit_network`` takes them."""
    def signal(n, periodic):
        return (rng.standard_normal((n, N_INPUTS)), rng.standard_normal((n, N_OUTPUTS)), np.ones(N_OUTPUTS),
                periodic, np.full(N_OUTPUTS, 0.01))
    return [signal(PERIOD, True) for _ in range(N_LEVELS)] + [signal(4 * SEGMENT, False) for _ in range(N_LEVELS)]


def product_flops():
    """The products' flops in an iteration: for each layer and sample, the
    complex weights B and C as real ones of 2 n_modes x width, forward
    (B v, C s) and back (dC, dB, and through each), and the mixing (forward,
    its gradient, through it)."""
    n_samples = N_LEVELS * (PERIOD + SEGMENT)
    return n_samples * N_LAYERS * (6 * 2 * (2 * N_MODES) * WIDTH + 3 * 2 * WIDTH * WIDTH)


def products_alone(repeat):
    """The same products as an iteration, on one BLAS thread (s)."""
    from sklearn_pnlss.utils.threads import one_blas_thread

    rng = np.random.default_rng(0)
    weights_in = rng.standard_normal((WIDTH, 2 * N_MODES)).astype(np.float32)
    weights_out = rng.standard_normal((2 * N_MODES, WIDTH)).astype(np.float32)
    mixing = rng.standard_normal((WIDTH, WIDTH)).astype(np.float32)
    batches = [(rng.standard_normal((n, WIDTH)).astype(np.float32),
                rng.standard_normal((n, 2 * N_MODES)).astype(np.float32)) for n in (N_LEVELS * PERIOD,
                                                                                     N_LEVELS * SEGMENT)]
    times = []
    with one_blas_thread():
        for _ in range(repeat):
            t0 = time.perf_counter()
            for v, s in batches:
                for _ in range(N_LAYERS):
                    v @ weights_in, s @ weights_out, v @ mixing  # forward
                    v.T @ s, v @ weights_out.T, s.T @ v, s @ weights_in.T, v.T @ v, v @ mixing.T  # back
            times.append(time.perf_counter() - t0)
    return min(times)


def iteration_time(n_networks, n_jobs, n_iter):
    """Wall time of an iteration of ``n_networks`` networks fitted
    ``n_jobs`` at a time (a first short fit starts the workers)."""
    from sklearn_pnlss.estimators._lru import fit_networks
    from sklearn_pnlss.estimators.lru_above_band import _above_cutoff

    signals = training_batch(np.random.default_rng(1))
    settings = (N_INPUTS, N_OUTPUTS, WIDTH, N_LAYERS, N_MODES)
    project = partial(_above_cutoff, 15.5, 400.0)
    seeds = [(2 * k, 2 * k + 1) for k in range(n_networks)]
    fit_networks(settings, signals, (2, 3e-3, SEGMENT, 4096), seeds, project, n_jobs)
    t0 = time.perf_counter()
    fit_networks(settings, signals, (n_iter, 3e-3, SEGMENT, 4096), seeds, project, n_jobs)
    return (time.perf_counter() - t0) / n_iter


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--output", default=RESULTS / "lru_iteration.json")
    args = parser.parse_args(argv)

    flops = product_flops()
    products_s = products_alone(5)
    one = iteration_time(1, None, args.iterations)
    pair = iteration_time(2, 2, args.iterations)
    results = {**header(), "network": {"n_inputs": N_INPUTS, "n_outputs": N_OUTPUTS, "width": WIDTH,
                                       "n_layers": N_LAYERS, "n_modes": N_MODES},
               "batch": {"periods": [N_LEVELS, PERIOD], "segments": [N_LEVELS, SEGMENT]},
               "product_gflop": flops / 1e9, "products_alone_s": products_s,
               "blas_gflops_one_thread": flops / products_s / 1e9,
               "iteration_s": one, "iteration_of_two_side_by_side_s": pair,
               "iteration_per_network_side_by_side_s": pair / 2}
    print(f"products: {flops / 1e9:.1f} GFlop an iteration, {products_s:.3f} s alone on one BLAS thread "
          f"({flops / products_s / 1e9:.0f} GFlop/s)")
    print(f"an iteration, one network on every core: {one:.3f} s ({products_s / one:.0%} of it the products' "
          f"time on one core)")
    print(f"an iteration of two networks side by side: {pair:.3f} s ({pair / 2:.3f} s a network)")
    write_results(results, args.output)


if __name__ == "__main__":
    main()
