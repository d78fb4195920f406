"""JSON output: the one converter every layer uses, strict by construction.

NumPy scalars and arrays become Python numbers and lists, tuples become lists, paths become
strings, dataclasses with a ``to_dict()`` method are converted through it, and non-finite floats
(NaN, +-Infinity) become ``null``: the output is valid JSON (RFC 8259) that any parser reads,
never Python's ``NaN`` extension. Anything else that JSON cannot hold is an error naming its
type, not a silent ``str()``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import PurePath
from typing import Any

import numpy as np

__all__ = ["dumps", "to_jsonable"]


def to_jsonable(obj: Any) -> Any:
    """``obj`` as plain JSON values: dict, list, str, int, float (finite), bool or None.

    Raises:
        TypeError: for a value JSON cannot represent (the message names its type).
    """
    if obj is None or isinstance(obj, (str, bool)):
        return obj
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, np.bool_):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, PurePath):
        return str(obj)
    to_dict = getattr(obj, "to_dict", None)
    if callable(to_dict):
        return to_jsonable(to_dict())
    raise TypeError(f"cannot write a {type(obj).__name__} as JSON")


def dumps(obj: Any, indent: int | None = 2) -> str:
    """Strict JSON text of ``obj`` (see :func:`to_jsonable`), with a trailing newline."""
    return json.dumps(to_jsonable(obj), indent=indent, allow_nan=False) + "\n"
