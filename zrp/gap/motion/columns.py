"""One-joint deviation columns of the motion effects (memory linear in the samples, not in
samples x joints).

Most motion parameters act on one joint: their deviation d and derivative D (S, n) are zero
except on that joint's column. :class:`JointColumn` stores that column only and gives the
dense array where one is asked for, so a search holding dozens of parameters at 1e6 samples
holds 8 MB each instead of 48 MB (issue 26: 5.3 GB at 1e6 rows).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from zrp.arrays import F64

__all__ = ["Deviation", "JointColumn", "combine"]


class JointColumn:
    """A joint deviation (S, n) that is zero except on 0-based joint ``k``, stored as that
    column (S,): memory 8 bytes a sample instead of 8 n (a search holds dozens of them; at
    1e6 samples the dense arrays took gigabytes). Indexing gives the dense rows
    (``basis[poses]`` -> (P, n), as :class:`~zrp.gap.model.problem.Problem` takes them);
    ``np.asarray`` and arithmetic give the dense array."""

    __slots__ = ("col", "k", "n")

    def __init__(self, n: int, k: int, col: F64) -> None:
        self.n, self.k, self.col = n, k, np.asarray(col, dtype=float)

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.col.shape[0]), self.n)

    ndim = 2

    def dense(self) -> F64:
        out = np.zeros(self.shape)
        out[:, self.k] = self.col
        return out

    def __getitem__(self, idx: Any) -> F64:
        if isinstance(idx, tuple):
            return self.dense()[idx]
        c = self.col[idx]
        out = np.zeros((*c.shape, self.n))
        out[..., self.k] = c
        return out

    def __array__(self, dtype: Any = None, copy: Any = None) -> F64:
        return self.dense() if dtype is None else self.dense().astype(dtype)

    def setflags(self, write: bool) -> None:
        self.col.setflags(write=write)

    def __add__(self, other: Any) -> F64:
        return self.dense() + np.asarray(other)

    __radd__ = __add__

    def __sub__(self, other: Any) -> F64:
        return self.dense() - np.asarray(other)

    def __rsub__(self, other: Any) -> F64:
        return np.asarray(other) - self.dense()

    def __mul__(self, other: Any) -> F64:
        return self.dense() * np.asarray(other)

    __rmul__ = __mul__

    def __neg__(self) -> F64:
        return -self.dense()


Deviation = F64 | JointColumn


def combine(a: Deviation, b: Deviation, scale: float = 1.0) -> Deviation:
    """a + scale b, kept on one joint when both are (values as the dense sum)."""
    if isinstance(a, JointColumn) and isinstance(b, JointColumn) and a.k == b.k:
        return JointColumn(a.n, a.k, a.col + b.col * scale)
    return np.asarray(a) + np.asarray(b) * scale
