"""Argument checks shared by the tolerance modules (:mod:`.tolerance`, :mod:`.population`,
:mod:`.allocation`): each error names the argument and what was expected."""

from __future__ import annotations

import numpy as np

from zrp.errors import InputError
from zrp.manufacturing.choices import DISTRIBUTIONS

__all__ = ["DISTRIBUTIONS", "check_distribution", "check_percentile", "nonnegative",
           "positive_int"]



def check_percentile(pct: float, name: str = "percentile") -> float:
    try:
        v = float(pct)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number in [0, 100], got {pct!r}") from exc
    if not 0.0 <= v <= 100.0:
        raise InputError(f"{name}: expected a number in [0, 100] (e.g. 99), got {pct!r}")
    return v


def check_distribution(distribution: str) -> str:
    if distribution not in DISTRIBUTIONS:
        raise InputError(f"distribution: {distribution!r} is unknown; expected one of "
                         f"{DISTRIBUTIONS}")
    return distribution


def positive_int(value: int, name: str, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def nonnegative(value: float, name: str, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {value!r}") from exc
    if not np.isfinite(v) or v < 0:
        raise InputError(f"{name}: expected a finite value >= 0 ({unit}), got {value!r}")
    return v
