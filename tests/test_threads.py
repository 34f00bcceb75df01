"""The library's own threads: BLAS limited while they run and restored
after, even when uses overlap; a recursion's columns shared out in spans."""
import threading

import pytest

from sklearn_pnlss.utils import threads
from sklearn_pnlss.utils.threads import one_blas_thread, over_column_spans


def test_overlapping_limits_restore_blas_when_the_last_ends(monkeypatch):
    """Two threads' uses that overlap, the first in ending last: BLAS is
    limited once, at the first entry, and restored once, at the last exit
    (threadpoolctl's limiter stood in for: what OpenBLAS reports from a new
    thread depends on where it last ran)."""
    calls = []

    class Limiter:
        def restore_original_limits(self):
            calls.append("restore")

    class Controller:
        def limit(self, limits, user_api):
            calls.append(("limit", limits, user_api))
            return Limiter()

    monkeypatch.setattr(threads, "_controller", lambda: Controller())
    inside, released = threading.Event(), threading.Event()
    seen = {}

    def first():  # in first, out last
        with one_blas_thread():
            inside.set()
            released.wait(5)

    def second():
        inside.wait(5)
        with one_blas_thread():
            pass
        seen["after the second's exit"] = list(calls)
        released.set()

    workers = [threading.Thread(target=first), threading.Thread(target=second)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    assert seen["after the second's exit"] == [("limit", 1, "blas")]
    assert calls == [("limit", 1, "blas"), "restore"]
    assert threads._LIMIT_USERS == 0


@pytest.mark.parametrize("blas, n_columns, min_span, spans", [
    (2, 1000, 256, [(0, 500), (500, 1000)]),
    (4, 1000, 256, [(0, 333), (333, 666), (666, 1000)]),  # no span narrower than min_span
    (2, 300, 256, [(0, 300)]),
    (1, 5000, 256, [(0, 5000)]),  # BLAS on one thread here: the caller's thread alone
])
def test_columns_are_shared_out_in_consecutive_spans(monkeypatch, blas, n_columns, min_span, spans):
    monkeypatch.setattr(threads, "blas_thread_count", lambda: blas)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 8)
    done, caller = [], threading.get_ident()

    def span(c0, c1):
        done.append((c0, c1, threading.get_ident() == caller))

    over_column_spans(span, n_columns, min_span)
    assert sorted(d[:2] for d in done) == spans
    assert [d[:2] for d in done if d[2]] == [spans[0]]  # the first in the caller's thread


@pytest.mark.parametrize("n_jobs, n_tasks, limited", [(2, 2, True), (3, 5, True), (None, 2, False),
                                                      (1, 4, False), (2, 1, False)])
def test_fits_side_by_side_limit_blas_only_when_several_run_at_once(monkeypatch, n_jobs, n_tasks, limited):
    """Fits in joblib threads (an AveragedRegressor's members, a decoupled
    model's starts) hold BLAS on one thread only when more than one runs
    at a time: one fit alone keeps BLAS's threads."""
    entered = []

    class Limiter:
        def restore_original_limits(self):
            pass

    class Controller:
        def limit(self, limits, user_api):
            entered.append((limits, user_api))
            return Limiter()

    monkeypatch.setattr(threads, "_controller", lambda: Controller())
    with threads.side_by_side_blas(n_jobs, n_tasks):
        pass
    assert entered == ([(1, "blas")] if limited else [])
