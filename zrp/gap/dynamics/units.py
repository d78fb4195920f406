"""Units of the torque log's columns, declared in the header as ``name [unit]`` (e.g.
``q1 [deg]``, ``tau3 [mNm]``, ``t [ms]``); a column without a bracket is in the SI unit of its
kind (listed in :data:`SI`), and the loader says so once with a warning.

Each kind maps unit names to the factor that converts a value to SI (value * factor).
"""

from __future__ import annotations

import math
import re

from zrp.errors import InputError

__all__ = ["KIND_UNITS", "SI", "split_unit", "unit_factor"]

KIND_UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    # joint values: rad for hinges, m for slides
    "position": {"rad": 1.0, "deg": math.pi / 180.0, "m": 1.0, "mm": 1e-3},
    "velocity": {"rad/s": 1.0, "deg/s": math.pi / 180.0, "m/s": 1.0, "mm/s": 1e-3},
    # N m for hinges, N for slides
    "effort": {"nm": 1.0, "n m": 1.0, "n.m": 1.0, "mnm": 1e-3, "n": 1.0},
    "current": {"a": 1.0, "ma": 1e-3},
    "mass": {"kg": 1.0, "g": 1e-3},
}

#: The unit a column without a declared unit is in (hinge joints; slides: m, m/s, N).
SI = {"time": "s", "position": "rad", "velocity": "rad/s", "effort": "Nm", "current": "A",
      "mass": "kg"}

_BRACKET = re.compile(r"^\s*([^\[\]\s]+)\s*(?:\[\s*([^\[\]]*?)\s*\])?\s*$")


def split_unit(header: str, src: str) -> tuple[str, str | None]:
    """(column name, declared unit or None) of a header field ``name [unit]``."""
    m = _BRACKET.match(header)
    if m is None:
        raise InputError(f"{src} line 1: column {header!r} is not 'name' or 'name [unit]'")
    return m.group(1), (m.group(2) or None)


def unit_factor(kind: str, unit: str | None, column: str, src: str) -> float:
    """The factor to SI of ``unit`` (a unit of ``kind``; None: SI)."""
    if unit is None:
        return 1.0
    table = KIND_UNITS[kind]
    key = unit.strip().lower()
    if key not in table:
        shown = ", ".join(sorted({SI[kind], *table}))
        raise InputError(f"{src} line 1: column {column} has unit [{unit}]; a {kind} "
                         f"column takes one of {shown}")
    return table[key]
