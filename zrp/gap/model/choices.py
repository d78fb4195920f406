"""The names of the diagnosis's candidate effects and registration (:mod:`.context`).

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["EFFECTS", "REGISTRATION"]

#: Candidate effects, in the order they are tried (ties are broken by this order).
EFFECTS = ("joint_offset", "encoder_scale", "link_length", "axis_misalignment",
           "joint_compliance", "backlash", "thermal_expansion", "cyclic_error")
REGISTRATION = ("base_frame", "tool_offset")
