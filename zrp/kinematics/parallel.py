"""Large batches of the compiled forward-kinematics and Jacobian kernels split across the cores.

The batch kernels (:func:`zrp.kinematics._kernels.fk_pose_batch`, ``jac_batch``) release the
GIL. A batch of at least :data:`MIN_FK_POSES` poses (:data:`MIN_JAC_POSES` for Jacobians) is
cut into one contiguous chunk per usable core, each run by the same kernel in a thread of a
shared pool, the calling thread taking the first. The chunks start at multiples of the
kernels' block of 256 poses, so every pose is computed by the same instructions at the same
place of its block as in one call over the whole batch: the result is bitwise the
single-threaded one (tests/kinematics/test_parallel.py). Smaller batches stay on the calling
thread: handing a chunk to another thread costs some tens of microseconds, the forward
kinematics of a few thousand poses.

The split saves wall time only when a second core is free; it costs no CPU time (the same
work, cut in two). ``threads=1`` keeps a call on the calling thread whatever its size.
"""

from __future__ import annotations

import itertools
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from zrp.errors import InputError

__all__ = ["MIN_FK_POSES", "MIN_JAC_POSES", "run_split", "thread_count", "usable_cores"]

#: Poses from which a forward-kinematics batch is split (~0.4 ms of one core's work).
MIN_FK_POSES = 32_768
#: Poses from which a Jacobian batch is split (about the same work as MIN_FK_POSES poses).
MIN_JAC_POSES = 8_192
_ALIGN = 256  # the batch kernels' block (zrp.kinematics._kernels._BLOCK)

_pool: tuple[ThreadPoolExecutor, int] | None = None  # the pool and its number of workers
_pool_lock = threading.Lock()


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity; the CPU count where the system
    has no affinity)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def thread_count(n_poses: int, min_poses: int, threads: int | None) -> int:
    """How many threads a batch of ``n_poses`` runs on: ``threads`` when given (at most one
    per block of poses), else every usable core from ``min_poses`` poses on and one below.

    Raises:
        InputError: ``threads`` not a positive integer.
    """
    if threads is not None:
        if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) \
                or threads < 1:
            raise InputError(f"threads: expected a positive integer or None (automatic), "
                             f"got {threads!r}")
        return max(1, min(int(threads), -(-n_poses // _ALIGN)))
    return usable_cores() if n_poses >= min_poses else 1


def _executor(workers: int) -> ThreadPoolExecutor:
    global _pool
    with _pool_lock:
        if _pool is None or _pool[1] < workers:  # grown on demand, then kept
            old = _pool
            _pool = (ThreadPoolExecutor(workers, thread_name_prefix="zrp-kinematics"), workers)
            if old is not None:
                old[0].shutdown(wait=False)
        return _pool[0]


def _bounds(n: int, parts: int) -> list[tuple[int, int]]:
    """``parts`` contiguous chunks of ``n`` poses, each starting at a multiple of the
    kernels' block (the last takes the rest); empty chunks left out."""
    blocks = -(-n // _ALIGN)
    cuts = [min(n, _ALIGN * (blocks * i // parts)) for i in range(parts + 1)]
    cuts[-1] = n
    return [(a, b) for a, b in itertools.pairwise(cuts) if b > a]


def run_split(kernel: Callable[..., bool], q: np.ndarray, shared: tuple, per_pose: tuple,
              threads: int) -> bool:
    """``kernel(q[a:b], *shared, *(x[a:b] for x in per_pose))`` over ``threads`` chunks of
    the poses (rows of ``q`` and of each ``per_pose`` array); True when every chunk's kernel
    returned True (its range check passed)."""
    chunks = _bounds(q.shape[0], threads) if threads > 1 else []
    if len(chunks) < 2:
        return bool(kernel(q, *shared, *per_pose))

    def one(a: int, b: int) -> bool:
        return bool(kernel(q[a:b], *shared, *(x[a:b] for x in per_pose)))

    pool = _executor(len(chunks) - 1)
    futures = [pool.submit(one, a, b) for a, b in chunks[1:]]
    ok = one(*chunks[0])
    return all([f.result() for f in futures]) and ok
