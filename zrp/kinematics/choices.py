"""The choices of the trajectory IK (:mod:`.ik`): correction schemes and tasks.

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["CORRECTIONS", "TASKS", "TIME_LAWS"]

CORRECTIONS = ("newton", "feedback", "none")
#: Time laws of a trajectory (:mod:`.trajectory`).
TIME_LAWS = ("quintic", "cycloidal")
TASKS = ("pose", "position")
