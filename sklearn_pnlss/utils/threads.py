"""The library's own threads: independent signals simulated side by side,
the independent columns of a recursion shared out, and BLAS on one thread
meanwhile."""
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, nullcontext
from functools import lru_cache

from joblib import effective_n_jobs
from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread", "blas_threads_for", "symmetric_threads_for", "side_by_side_blas", "each_in_threads",
           "over_column_spans"]

_CONTROLLER = None  # made once: each one scans the loaded libraries (tens of ms)
_LIMIT_LOCK = threading.Lock()
_LIMIT = None  # the limit one_blas_thread holds, and how many hold it
_LIMIT_USERS = 0


@contextmanager
def one_blas_thread():
    """Context manager: BLAS single-threaded (process-wide) for its
    duration, restored after.

    Where the library runs its own threads (segments of a Jacobian, the
    candidates of a gap diagnosis), a multithreaded BLAS in each of them
    oversubscribes the cores, and OpenBLAS's waiting threads spin: measured
    on 2 cores, a gap diagnosis took 31.5 s of wall time and 59 s of CPU,
    21.4 s and 38 s with one BLAS thread; 20 Bouc-Wen realisations took
    10 s per 10 iterations instead of 4 s.

    Counted, so that overlapping uses from several threads (two fits side
    by side, each over its own signals) restore BLAS only when the last one
    ends: each restoring what it found would leave BLAS on one thread when
    the first one in ends last.
    """
    global _LIMIT, _LIMIT_USERS
    with _LIMIT_LOCK:
        if _LIMIT_USERS == 0:
            _LIMIT = _controller().limit(limits=1, user_api="blas")
        _LIMIT_USERS += 1
    try:
        yield
    finally:
        with _LIMIT_LOCK:
            _LIMIT_USERS -= 1
            if _LIMIT_USERS == 0:
                _LIMIT.restore_original_limits()


def _controller():
    global _CONTROLLER
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def blas_thread_count():
    """The threads BLAS may use here and now: one inside
    :func:`one_blas_thread` (the library's threads over signals), a worker's
    share inside a joblib grid search, all cores by default."""
    return max((lib.num_threads for lib in _controller().select(user_api="blas").lib_controllers), default=1)


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


#: The order of a symmetric product above which it runs on one BLAS thread:
#: a Gram matrix ``X^T X`` (syrk) or a Cholesky factorisation (potrf, whose
#: updates are syrk too). OpenBLAS's threaded kernels (as the numpy and scipy
#: wheels ship them) ended the process with a segmentation fault on 2 cores
#: here: a factorisation from an order of 16,384 (15,500 passed; on one
#: thread 17,000 passed), in numpy and scipy alike, and numpy's ``A.T @ A``
#: of a 796 x 17,000 ``A`` (200 x 17,000 passed), a crash of its threaded
#: kernels on large matrices that its tracker has seen since its first
#: releases (``tests/test_above_band.py`` holds a fit of an order of 16,200).
#: Below the bound every core is kept: the F-16's filters past three
#: clearances, an order of 7,400, are solved in about 4 s on 2 cores.
LARGE_SYMMETRIC_ORDER = 12_000


def symmetric_threads_for(order):
    """Context manager: :func:`one_blas_thread` for a Gram matrix or a
    Cholesky factorisation of ``order`` above
    :data:`LARGE_SYMMETRIC_ORDER`, BLAS as configured otherwise."""
    return one_blas_thread() if order > LARGE_SYMMETRIC_ORDER else nullcontext()


def side_by_side_blas(n_jobs, n_tasks):
    """Context manager for ``n_tasks`` fits run ``n_jobs`` at a time in
    joblib threads: :func:`one_blas_thread` when more than one runs at
    once, BLAS as configured otherwise.

    Each fit then keeps one core, as in a process of its own. With BLAS
    threaded in each, their Gram matrices contended for the same cores:
    two F-16 decoupled fits side by side (18 states, 525 parameters) took
    123 s, 66 s on one BLAS thread each, with the same models to four
    digits (``benchmarks/bench_side_by_side.py``).
    """
    return one_blas_thread() if min(effective_n_jobs(n_jobs), n_tasks) > 1 else nullcontext()


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


@lru_cache(maxsize=1)
def _span_pool():
    """The threads that share out a recursion's columns, made once (apart
    from ``_pool``: a span never waits on a signal's thread, nor one on it)."""
    return ThreadPoolExecutor(max_workers=max(1, (os.cpu_count() or 1) - 1), thread_name_prefix="spans")


def over_column_spans(func, n_columns, min_span):
    """``func(c0, c1)`` on consecutive spans of ``range(n_columns)``, side by
    side: as many spans as BLAS may use threads here (see
    :func:`blas_thread_count`), none narrower than ``min_span``.

    For a recursion whose columns are independent (the sensitivities of a
    Jacobian, one column per parameter): it runs on the cores that the
    Jacobian's Gram matrix gets from BLAS, where it would otherwise keep one
    busy and leave the rest idle. Inside the library's threads over signals
    (BLAS on one thread there) it runs whole, in the caller's thread.

    BLAS is left as configured meanwhile, as fast (F-16 normal equations
    4.38 s against 4.46 s with it limited) and without a process-wide
    switch per block: the products of a span stay below the size OpenBLAS
    threads (the F-16's sensitivities: 13 x 10 times 10 x 1,435, 187,000
    multiply-adds).
    """
    k = max(1, min(blas_thread_count(), os.cpu_count() or 1, n_columns // max(1, min_span)))
    if k == 1:
        func(0, n_columns)
        return
    edges = [n_columns * i // k for i in range(k + 1)]
    others = [_span_pool().submit(func, a, b) for a, b in zip(edges[1:-1], edges[2:])]
    func(edges[0], edges[1])
    for f in others:
        f.result()
