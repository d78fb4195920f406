"""The names of the motion diagnosis's effects (:mod:`.effects`).

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["MOTION_EFFECTS"]

MOTION_EFFECTS = ("sync_delay", "servo_lag", "reversal_friction", "dynamic_compliance",
                  "residual_vibration")
