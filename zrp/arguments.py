"""Checks of public API arguments: one place for "a whole number >= 0", "a seed", "a model".

Each raises :class:`~zrp.errors.InputError` naming the Python argument and what was expected,
so that a wrong type (``None``, ``1.5``, a string) never reaches NumPy as a bare ``TypeError``.
The command line has its own converters (``zrp.cli.options``) with the same rules.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from zrp.errors import InputError
from zrp.limits import MAX_SEED

__all__ = ["MAX_SEED", "check_float", "check_instance", "check_int", "check_seed"]



def _whole(value: object) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def check_int(value: object, name: str, minimum: int | None = None,
              maximum: int | None = None) -> int:
    """``value`` as an int, a whole number (not a bool or a float) in [minimum, maximum]."""
    if not _whole(value):
        raise InputError(f"{name}: expected a whole number, got {value!r}")
    v = int(value)  # type: ignore[call-overload]
    if (minimum is not None and v < minimum) or (maximum is not None and v > maximum):
        lo = "" if minimum is None else f">= {minimum}"
        hi = "" if maximum is None else f"<= {maximum}"
        raise InputError(f"{name}: expected a whole number {' and '.join(x for x in (lo, hi) if x)}"
                         f", got {v}")
    return v


def check_seed(value: object, name: str = "seed") -> int:
    """A random seed: a whole number in [0, :data:`MAX_SEED`]."""
    return check_int(value, name, 0, MAX_SEED)


def check_float(value: object, name: str, lo: float = -math.inf, hi: float = math.inf, *,
                open_lo: bool = False, open_hi: bool = False, unit: str = "") -> float:
    """``value`` as a finite float in [lo, hi] (open ends with ``open_lo``/``open_hi``)."""
    if not isinstance(value, numbers.Real) or isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected a number, got {value!r}")
    v = float(value)
    ok = math.isfinite(v) and (v > lo if open_lo else v >= lo) and (v < hi if open_hi else v <= hi)
    if not ok:
        left = "(" if open_lo else "["
        right = ")" if open_hi else "]"
        raise InputError(f"{name}: expected a finite number in {left}{lo:g}, {hi:g}{right}"
                         f"{' ' + unit if unit else ''}, got {value!r}")
    return v


def check_instance(value: Any, cls: type, name: str, what: str) -> Any:
    """``value`` itself when it is a ``cls``; else an error naming ``name`` and ``what``."""
    if not isinstance(value, cls):
        raise InputError(f"{name}: expected {what}, got {type(value).__name__}")
    return value
