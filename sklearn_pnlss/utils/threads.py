"""BLAS on one thread where the library runs threads of its own."""
from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread"]

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
