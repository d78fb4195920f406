"""Map independent tasks over any ``concurrent.futures``-style executor, or over none.

The one scheduling loop of the toolkit: the Monte Carlo chunks (:mod:`zrp.manufacturing.chunks`),
the blind benchmark's scenarios (:mod:`sim.benchmark.runner`) and the fleet diagnosis
(:mod:`zrp.cli.fleet`) all go through :func:`map_tasks`. The core never imports an executor
library: the application passes one in (a Dask ``Client.get_executor()`` from
:mod:`zrp.cli.cluster`, a ``ProcessPoolExecutor``, ...). Results come back in completion order,
so a caller can write each one as it arrives and a progress bar advances with the workers.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass
from typing import Any, TypeVar

__all__ = ["TaskFailure", "map_tasks"]

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
        return {"position": self.position, "task": self.task, "error": self.error}


def _failure(position: int, task: Any, exc: BaseException,
             describe: Callable[[Any], str]) -> TaskFailure:
    return TaskFailure(position, describe(task), f"{type(exc).__name__}: {exc}",
                       "".join(traceback.format_exception(exc)))


def map_tasks(fn: Callable[[T], R], tasks: Sequence[T], executor: Executor | Any | None = None,
              *, capture: bool = False, describe: Callable[[Any], str] = repr
              ) -> Iterator[tuple[int, R | TaskFailure]]:
    """``(position, fn(task))`` for every task, in completion order.

    Args:
        fn: a picklable (module-level) function of one task.
        tasks: the inputs.
        executor: None (run here, in order) or anything whose ``submit`` returns
            ``concurrent.futures.Future``-compatible futures; every task is submitted at once.
        capture: a task that raises yields a :class:`TaskFailure` (naming its input through
            ``describe``) and the others still run; without it the first error is raised and
            the tasks not yet started are cancelled.
    """
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
    futures = {executor.submit(fn, task): i for i, task in enumerate(tasks)}
    try:
        for fut in as_completed(futures):
            i = futures[fut]
            try:
                res = fut.result()
            except Exception as exc:  # raised on the worker, or the worker died
                if not capture:
                    raise
                res = _failure(i, tasks[i], exc, describe)
            yield i, res
    finally:
        for fut in futures:
            fut.cancel()
