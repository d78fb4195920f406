"""Map independent tasks over any ``concurrent.futures``-style executor, or over none.

The one scheduling loop of the toolkit: the Monte Carlo chunks (:mod:`zrp.manufacturing.chunks`),
the blind benchmark's scenarios (:mod:`sim.studies.benchmark.runner`) and the fleet diagnosis
(:mod:`zrp.cli.fleet`) all go through :func:`map_tasks`. The core never imports an executor
library: the application passes one in (a Dask ``Client.get_executor()`` from
:mod:`zrp.cli.cluster`, a ``ProcessPoolExecutor``, ...). Results come back in completion order,
so a caller can write each one as it arrives and a progress bar advances with the workers.
"""

from __future__ import annotations

import queue
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future
from dataclasses import dataclass
from itertools import islice
from typing import Any, TypeVar

from zrp.errors import InputError

__all__ = ["WINDOW", "TaskFailure", "map_tasks"]

T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True)
class TaskFailure:
    """A task that raised: its position in the task list, a description of its input, the
    error (``Type: message``) and the traceback text."""

    position: int
    task: str
    error: str
    traceback: str

    def to_dict(self) -> dict[str, Any]:
        from zrp.jsonio import dict_from_dataclass  # NumPy: on use (quick `zrp --help`)

        return dict_from_dataclass(self, exclude=("traceback",))


def _failure(position: int, task: Any, exc: BaseException,
             describe: Callable[[Any], str]) -> TaskFailure:
    return TaskFailure(position, describe(task), f"{type(exc).__name__}: {exc}",
                       "".join(traceback.format_exception(exc)))


#: Tasks in flight at once on an executor: enough to keep ~500 single-thread workers busy,
#: few enough that the pickled inputs waiting on the scheduler stay small (a Monte Carlo chunk
#: task is ~110 KB: ~110 MB in flight, where submitting the 36,000 chunks of 1e9 robots at once
#: would put ~4 GB on the client and the scheduler).
WINDOW = 1024


def map_tasks(fn: Callable[[T], R], tasks: Sequence[T], executor: Executor | Any | None = None,
              *, capture: bool = False, describe: Callable[[Any], str] = repr,
              window: int = WINDOW) -> Iterator[tuple[int, R | TaskFailure]]:
    """``(position, fn(task))`` for every task, in completion order.

    Args:
        fn: a picklable (module-level) function of one task.
        tasks: the inputs.
        executor: None (run here, in order) or anything whose ``submit`` returns
            ``concurrent.futures.Future``-compatible futures.
        capture: a task that raises yields a :class:`TaskFailure` (naming its input through
            ``describe``) and the others still run; without it the first error is raised and
            the tasks not yet started are cancelled.
        window: at most this many tasks in flight (>= 1; one more while a result is handed
            over): the next task is submitted as each result comes back, so the memory held
            by inputs and results in flight does not grow with the number of tasks.
    """
    if isinstance(window, bool) or not isinstance(window, int) or window < 1:
        raise InputError(f"window: expected an integer >= 1, got {window!r}")
    if executor is None:
        for i, task in enumerate(tasks):
            try:
                res: R | TaskFailure = fn(task)
            except Exception as exc:
                if not capture:
                    raise
                res = _failure(i, task, exc, describe)
            yield i, res
        return
    futures: dict[Future[Any], int] = {}
    finished: queue.SimpleQueue[Future[Any]] = queue.SimpleQueue()  # O(1) a task, any window
    queued = iter(range(len(tasks)))

    def submit(j: int) -> None:
        fut = executor.submit(fn, tasks[j])
        futures[fut] = j
        fut.add_done_callback(finished.put)

    try:
        for i in islice(queued, window):
            submit(i)
        while futures:
            fut = finished.get()
            i = futures.pop(fut)
            try:
                res = fut.result()
            except Exception as exc:  # raised on the worker, or the worker died
                if not capture:
                    raise
                res = _failure(i, tasks[i], exc, describe)
            for j in islice(queued, 1):  # refill before handing over: workers stay busy
                submit(j)
            yield i, res
    finally:
        for fut in futures:
            fut.cancel()
