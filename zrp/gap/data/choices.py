"""Limits of the data a diagnosis takes: rows read (:mod:`.csvfile`), points used
(:mod:`.subsample`) and the share of poses withheld (:mod:`zrp.gap.options`).

A light module (no NumPy, SciPy or numba): the command line states them in its help without
importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["MAX_POINTS", "MAX_ROWS", "MAX_WITHHELD"]

#: Most data rows read by default: about 0.7 GB of memory per million rows at the peak of a
#: whole diagnosis, so two million stay within 2 GB.
MAX_ROWS = 2_000_000
#: Default most measured points (rows) a diagnosis uses; beyond it a subsample of poses.
MAX_POINTS = 5000
#: Largest share of poses withheld: at least half of them remain for fitting and ranking.
MAX_WITHHELD = 0.5
