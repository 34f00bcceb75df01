"""The library's own threads: independent signals simulated side by side,
and BLAS on one thread meanwhile."""
import os
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from functools import lru_cache

from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread", "blas_threads_for", "each_in_threads"]

_CONTROLLER = None  # made once: each one scans the loaded libraries (tens of ms)


def one_blas_thread():
    """Context manager: BLAS single-threaded (process-wide) for its
    duration, restored after.

    Where the library runs its own threads (segments of a Jacobian, the
    candidates of a gap diagnosis), a multithreaded BLAS in each of them
    oversubscribes the cores, and OpenBLAS's waiting threads spin: measured
    on 2 cores, a gap diagnosis took 31.5 s of wall time and 59 s of CPU,
    21.4 s and 38 s with one BLAS thread; 20 Bouc-Wen realisations took
    10 s per 10 iterations instead of 4 s.
    """
    global _CONTROLLER
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")


#: Floating-point operations of a linear-algebra step below which BLAS threads
#: cannot pay: measured on 2 cores, a QR of 20,000 x 80 (2.6e8 flops) and a
#: Gram matrix of 8,192 x 64 gained nothing from the second thread alone,
#: and between compiled kernels the waiting threads cost more: in the
#: 10-iteration Bouc-Wen fit the BLA's 8,192 x 12 QR took 6 ms a call with
#: default threads against 0.15 ms with one.  Used by the BLA's subspace
#: step only: the Levenberg-Marquardt fits keep BLAS as configured (EMPS's
#: fit moved from 3.39 to 10.4 mm on its test split by the round-off alone).
SMALL_BLAS_FLOPS = 2e8


def blas_threads_for(flops):
    """Context manager: :func:`one_blas_thread` for a step of ``flops``
    below :data:`SMALL_BLAS_FLOPS`, BLAS as configured otherwise."""
    return one_blas_thread() if flops < SMALL_BLAS_FLOPS else nullcontext()


@lru_cache(maxsize=1)
def _pool():
    """The threads independent signals are simulated in, made once."""
    return ThreadPoolExecutor(max_workers=os.cpu_count(), thread_name_prefix="signals")


def each_in_threads(func, *columns):
    """``func`` on each row of the zipped ``columns`` (one signal each), in
    parallel threads, results in order.  The compiled integrators release
    the GIL, so the signals of a set keep every core busy when a single
    candidate is simulated (a refinement, the last long fit of a pool)."""
    rows = list(zip(*columns))
    if len(rows) < 2 or (os.cpu_count() or 1) < 2:
        return [func(*row) for row in rows]
    return [f.result() for f in [_pool().submit(func, *row) for row in rows]]
