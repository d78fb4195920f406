"""zrp.tasks.map_tasks: every task once, in completion order, with a bounded window of tasks
in flight (the memory of a 36,000-chunk Monte Carlo must not be submitted at once)."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from zrp.errors import InputError
from zrp.tasks import TaskFailure, map_tasks


class CountingExecutor:
    """A thread pool that records how many submitted tasks the caller has not yet taken."""

    def __init__(self, workers: int) -> None:
        self.pool = ThreadPoolExecutor(workers)
        self.lock = threading.Lock()
        self.outstanding = 0
        self.most = 0
        self.submitted = 0

    def submit(self, fn, *args):
        with self.lock:
            self.outstanding += 1
            self.submitted += 1
            self.most = max(self.most, self.outstanding)
        return self.pool.submit(fn, *args)

    def taken(self) -> None:
        with self.lock:
            self.outstanding -= 1


def _square(x: int) -> int:
    if x == 13:
        raise ValueError("thirteen")
    return x * x


def test_window_bounds_the_tasks_in_flight_and_every_task_comes_back_once():
    ex = CountingExecutor(3)
    got = {}
    for i, res in map_tasks(_square, list(range(200)), ex, window=5, capture=True):
        got[i] = res
        ex.taken()
    assert ex.submitted == 200 and ex.most <= 5 + 1  # +1: refilled just before handing over
    assert sorted(got) == list(range(200))
    assert all(got[i] == i * i for i in got if i != 13)
    assert isinstance(got[13], TaskFailure) and "thirteen" in got[13].error
    ex.pool.shutdown()


def test_without_an_executor_the_tasks_run_here_in_order_and_a_bad_window_is_refused():
    assert [i for i, _ in map_tasks(_square, [1, 2, 3])] == [0, 1, 2]
    with pytest.raises(ValueError, match="thirteen"):
        list(map_tasks(_square, [13]))
    with pytest.raises(InputError, match="window: expected an integer >= 1"):
        list(map_tasks(_square, [1], ThreadPoolExecutor(1), window=0))


def test_an_error_stops_the_run_and_cancels_what_was_not_started():
    ex = CountingExecutor(1)
    with pytest.raises(ValueError, match="thirteen"):
        for _ in map_tasks(_square, [13, *range(100)], ex, window=4):
            ex.taken()
    assert ex.submitted <= 4  # the 100 others were never submitted
    ex.pool.shutdown()
