"""A fixed-bin histogram of per-robot maxima that merges exactly: the worker-side reduction
of a Monte Carlo too large to gather robot by robot (:mod:`.reduction`).

Bins are geometric (constant relative width) between ``edges[0]`` and ``edges[-1]``, with an
underflow bin below and an overflow bin above; the exact count, minimum, maximum, sum and sum
of squares travel with the counts. Merging adds counts (integers: the merged histogram is
the same whatever the order of the chunks) and takes the extremes. A percentile is known to
the width of the bin that holds it: :meth:`Histogram.percentile` returns the bracket with the
estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64, I64
from zrp.errors import InputError
from zrp.manufacturing._checks import check_percentile

__all__ = ["Histogram", "geometric_edges"]



def geometric_edges(lo: float, hi: float, bins: int) -> F64:
    """``bins + 1`` edges from ``lo`` to ``hi`` (0 < lo < hi), constant ratio between
    neighbours, shape (bins + 1,)."""
    if not (0.0 < lo < hi < math.inf) or int(bins) < 1:
        raise InputError(f"edges: expected 0 < lo < hi and bins >= 1, got lo={lo!r}, "
                         f"hi={hi!r}, bins={bins!r}")
    return np.geomspace(lo, hi, int(bins) + 1)


@dataclass(frozen=True, eq=False)
class Histogram:
    """Counts of nonnegative values over fixed edges.

    Attributes:
        edges: bin edges, increasing, > 0, shape (B + 1,).
        counts: [below edges[0], the B bins, at or above edges[-1]], shape (B + 2,).
        total: number of values (the sum of counts).
        minimum, maximum: exact extremes (nan when empty).
        sum, sumsq: sum of the values and of their squares (mean and standard deviation).
    """

    edges: F64
    counts: I64
    total: int
    minimum: float
    maximum: float
    sum: float
    sumsq: float

    def __post_init__(self) -> None:
        e = np.asarray(self.edges, dtype=float)
        c = np.asarray(self.counts, dtype=np.int64)
        if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0) or e[0] <= 0:
            raise InputError("Histogram.edges: expected increasing positive edges, shape "
                             "(B + 1,) with B >= 1")
        if c.shape != (e.size + 1,) or np.any(c < 0) or int(c.sum()) != self.total:
            raise InputError(f"Histogram.counts: expected {e.size + 1} counts >= 0 summing to "
                             f"total={self.total}")
        object.__setattr__(self, "edges", e)
        object.__setattr__(self, "counts", c)

    @classmethod
    def of(cls, values: ArrayLike, edges: ArrayLike) -> Histogram:
        """The histogram of ``values`` (finite, >= 0; shape (N,)) over ``edges``."""
        v = np.asarray(values, dtype=float).ravel()
        e = np.asarray(edges, dtype=float)
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise InputError("values: expected finite values >= 0")
        counts = np.bincount(np.searchsorted(e, v, side="right"), minlength=e.size + 1)
        empty = v.size == 0
        return cls(e, counts.astype(np.int64), int(v.size),
                   math.nan if empty else float(v.min()), math.nan if empty else float(v.max()),
                   float(v.sum()), float(v @ v))

    def merge(self, other: Histogram) -> Histogram:
        """The histogram of both value sets (same edges required)."""
        if not isinstance(other, Histogram) or not np.array_equal(self.edges, other.edges):
            raise InputError("other: expected a Histogram over the same edges")
        return Histogram(self.edges, self.counts + other.counts, self.total + other.total,
                         float(np.fmin(self.minimum, other.minimum)),
                         float(np.fmax(self.maximum, other.maximum)),
                         self.sum + other.sum, self.sumsq + other.sumsq)

    @property
    def mean(self) -> float:
        return self.sum / self.total if self.total else math.nan

    @property
    def relative_width(self) -> float:
        """Relative width of a bin (edges[i+1] / edges[i] - 1)."""
        return float(self.edges[1] / self.edges[0] - 1.0)

    def _bin_range(self, j: int) -> tuple[float, float]:
        lo = self.minimum if j == 0 else self.edges[j - 1]
        hi = self.maximum if j == self.edges.size else self.edges[j]
        return float(max(lo, self.minimum)), float(min(hi, self.maximum))

    def order_statistic(self, k: int) -> tuple[float, float]:
        """[lo, hi] holding the ``k``-th smallest value (0-based, 0 <= k < total): the
        range of its bin, or the exact value for the extremes."""
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or \
                not 0 <= k < self.total:
            raise InputError(f"k: expected a rank 0 <= k < {self.total}, got {k!r}")
        if k == 0 or k == self.total - 1:
            x = self.minimum if k == 0 else self.maximum
            return x, x
        j = int(np.searchsorted(np.cumsum(self.counts), int(k), side="right"))
        return self._bin_range(j)

    def percentile(self, pct: float) -> tuple[float, float, float]:
        """(estimate, lo, hi) of the ``pct`` percentile (NumPy's linear definition): the
        exact percentile of the values lies in [lo, hi], the bins holding the order
        statistics it interpolates; the estimate interpolates linearly within them."""
        check_percentile(pct)
        if self.total == 0:
            raise InputError("percentile: the histogram is empty")
        h = (self.total - 1) * pct / 100.0
        if h == 0 or h == self.total - 1:  # the extremes are kept exactly
            x = self.minimum if h == 0 else self.maximum
            return x, x, x
        cum = np.cumsum(self.counts)
        ja = int(np.searchsorted(cum, math.floor(h), side="right"))
        jb = int(np.searchsorted(cum, math.ceil(h), side="right"))
        lo, hi_a = self._bin_range(ja)
        hi = self._bin_range(jb)[1]
        before = cum[ja] - self.counts[ja]
        frac = (h - before + 0.5) / self.counts[ja]
        est = lo + (hi_a - lo) * min(max(frac, 0.0), 1.0)
        return float(min(max(est, lo), hi)), lo, hi
