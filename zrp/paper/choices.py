"""The paper example's named settings: the PUMA's start and circle (:mod:`.scenario`), the
circles (:mod:`.example`) and the orientation laws (:mod:`.placement`).

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["CIRCLES", "ORIENTATION_LAWS", "PUMA_DURATION_S", "PUMA_Q0_DEG", "PUMA_RADIUS_MM"]

#: The start configuration chosen for the paper's PUMA (deg).
PUMA_Q0_DEG = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)
#: The circle's radius (mm) and duration (s), as in the paper.
PUMA_RADIUS_MM = 125.0
PUMA_DURATION_S = 4.0
#: The circles the example runs on: the paper's start as chosen, or recovered from Tables 2-3.
CIRCLES = ("default", "recovered")
#: How the hand turns along the recovered circle.
ORIENTATION_LAWS = ("held", "turning")
