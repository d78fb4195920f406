"""Batched forward kinematics split across the cores (issue 34).

The compiled batch kernel (:func:`zrp.kinematics._kernels.fk_pose_batch`) runs without the
GIL (``nogil``), so a large batch is cut into one contiguous slab of poses per thread (slab
edges on the kernel's block size) and the slabs run at once: the calling thread does the
first, a small persistent pool the others. Below :data:`SPLIT_MIN` poses one call does it all
(a thread hand-off costs tens of microseconds; the kernel does about 1e5 poses a millisecond).
The number of threads is numba's (``NUMBA_NUM_THREADS``, default: the cores) limited to the
cores this process may use; ``NUMBA_NUM_THREADS=1`` keeps every batch on one core.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from zrp.arrays import F64

__all__ = ["SPLIT_MIN", "n_threads", "split_batch"]

#: poses from which a batch is split across the threads.
SPLIT_MIN = 200_000
_ALIGN = 256  # the kernel's block of poses
_POOL: list[ThreadPoolExecutor] = []
if hasattr(os, "register_at_fork"):  # a forked child has none of the pool's threads
    os.register_at_fork(after_in_child=_POOL.clear)


def n_threads() -> int:
    """Threads a large batch uses: numba's setting, at most the cores this process may use."""
    import numba

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
        os.cpu_count() or 1)
    return max(1, min(int(numba.config.NUMBA_NUM_THREADS), cores))


def _pool(k: int) -> list[ThreadPoolExecutor]:
    if len(_POOL) < k:  # one worker per extra thread, kept for the next call
        _POOL.extend(ThreadPoolExecutor(max_workers=1, thread_name_prefix="zrp-fk")
                     for _ in range(k - len(_POOL)))
    return _POOL


def split_batch(kernel: Callable[..., bool], q: F64, args: tuple[object, ...], out: F64
                ) -> bool:
    """``kernel(q, *args, out)`` on slabs of the rows of ``q`` and ``out`` (C-contiguous,
    rows are poses), one per thread (:func:`n_threads`) when there are at least
    :data:`SPLIT_MIN` poses; True when every slab's call returned True."""
    N = q.shape[0]
    k = n_threads() if N >= SPLIT_MIN else 1
    if k < 2:
        return bool(kernel(q, *args, out))
    edges = [min(N, ((N * i // k) + _ALIGN - 1) // _ALIGN * _ALIGN) for i in range(k)] + [N]
    slabs = list(itertools.pairwise(edges))
    futures = [ex.submit(kernel, q[a:b], *args, out[a:b])
               for ex, (a, b) in zip(_pool(k - 1), slabs[1:], strict=False)]
    ok = bool(kernel(q[edges[0]:edges[1]], *args, out[edges[0]:edges[1]]))
    return all([bool(f.result()) for f in futures]) and ok

