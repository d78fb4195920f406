"""How many threads the BLAS/LAPACK under NumPy and SciPy may use: one home for that choice.

The diagnosis works on many small dense problems (Gram matrices of a few dozen columns,
``eigh`` of 50 x 50, tall products of ~9,000 x 50). OpenBLAS splits each of them over every
core and its threads spin while they wait for one another; on the 2-core machine under load
that made one 50 x 50 ``eigh`` 33 ms instead of 0.4 ms and one diagnosis of the IRB 120 data
3.3x slower than on one BLAS thread (``tests/benchmarks/bench_speed.py``). :func:`blas_threads`
limits the threads for a block of work and restores them after (through threadpoolctl, which
finds the BLAS libraries NumPy and SciPy actually loaded); it does nothing when threadpoolctl
is missing. Summation order inside the BLAS may change with the thread count: results agree
to rounding (measured: every number of a diagnosis within 1.2e-8 relative, verdicts equal).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["blas_threads"]


@contextmanager
def blas_threads(limit: int = 1) -> Iterator[None]:
    """Run the block with at most ``limit`` BLAS/LAPACK threads (restored on exit)."""
    try:
        from threadpoolctl import threadpool_limits  # optional: the toolkit runs without it
    except ImportError:
        yield
        return
    with threadpool_limits(limits=int(limit), user_api="blas"):
        yield
