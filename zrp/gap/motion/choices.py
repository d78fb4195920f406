"""The names of the motion diagnosis's effects (:mod:`.effects`).

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["MOTION_EFFECTS", "RATE_RANGE_HZ", "TIME_UNITS"]

MOTION_EFFECTS = ("sync_delay", "servo_lag", "reversal_friction", "dynamic_compliance",
                  "residual_vibration")

#: plausible median sample rates of a tracker stream, Hz: laser trackers and optical
#: trackers stream at 10 Hz to a few kHz; below 5 Hz the motion effects (ms delays and lags,
#: vibration) cannot be resolved, and above 100 kHz the time stamps are not in seconds.
RATE_RANGE_HZ = (5.0, 100_000.0)

#: time stamp units of a trajectory CSV, in s.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
