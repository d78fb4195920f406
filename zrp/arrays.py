"""Array type aliases, the one home for them: NumPy arrays of one dtype, any shape; and the
recycled result buffers of the batched kernels (:func:`recycled_empty`).

Shapes are given in each function's docstring (pytransform3d style), e.g. ``(n, 3)``.
"""

from __future__ import annotations

import sys
import threading

import numpy as np
from numpy.typing import NDArray

__all__ = ["F64", "I64", "RECYCLE_MIN_BYTES", "U8", "recycled_empty"]

#: float64 array of any shape.
F64 = NDArray[np.float64]
#: int64 array of any shape.
I64 = NDArray[np.int64]
#: uint8 array of any shape (images).
U8 = NDArray[np.uint8]


#: Results at least this large are recycled by :func:`recycled_empty` (smaller ones come from
#: malloc's own free lists, already faulted in).
RECYCLE_MIN_BYTES = 1 << 20
_POOL = threading.local()


def _free_refs() -> int:
    """getrefcount of an array held by a list only (the interpreter's own count: 2 on
    CPython up to 3.13, with getrefcount's argument)."""
    holder = [np.empty(0)]
    return sys.getrefcount(holder[0])


_FREE_REFS = _free_refs()


def recycled_empty(shape: tuple[int, ...]) -> NDArray[np.float64]:
    """A float64 C-contiguous array of ``shape`` with undefined contents, like ``np.empty``,
    but reusing a buffer this thread handed out before once nobody holds it (nor a view of
    it) any more.

    Why: a fresh array of more than ~32 MB is new memory from the OS, and the OS zero-fills
    each of its pages on first touch, which costs a third of the batched forward kinematics
    (1e6 poses: 56 MB). Each thread keeps at most the two last buffers of one size, so the
    usual loop ``p, er = end_effector_pose(model, q)`` (the previous result held while the next
    is computed) alternates between them; a buffer still referenced is never reused. Costs:
    up to two buffers of the last size stay allocated per thread.
    """
    nbytes = 8 * int(np.prod(shape))
    if nbytes < RECYCLE_MIN_BYTES:
        return np.empty(shape)
    pool = getattr(_POOL, "buffers", None)
    if pool is None or (pool and pool[0].nbytes != nbytes):
        pool = _POOL.buffers = []
    for i in range(len(pool)):
        if sys.getrefcount(pool[i]) == _FREE_REFS:  # held by the pool only
            return pool[i].reshape(shape)
    buf = np.empty(shape)
    pool.append(buf)
    del pool[:-2]
    return buf
