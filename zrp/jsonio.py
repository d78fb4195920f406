"""JSON output: the one converter every layer uses, strict by construction.

NumPy scalars and arrays become Python numbers and lists, tuples become lists, paths become
strings, dataclasses with a ``to_dict()`` method are converted through it, and non-finite floats
(NaN, +-Infinity) become ``null``: the output is valid JSON (RFC 8259) that any parser reads,
never Python's ``NaN`` extension. Anything else that JSON cannot hold is an error naming its
type, not a silent ``str()``.

:func:`dict_from_dataclass` is the one way a result dataclass writes its ``to_dict()``: its
fields in declaration order, renamed or left out where the JSON schema says so.

:func:`version_field` is the one way a reader checks a file's format version: an integer
among the known ones (``true`` is not version 1, though Python's ``True == 1``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Collection, Mapping
from pathlib import PurePath
from typing import Any

import numpy as np

from zrp.errors import InputError, ZRPError

__all__ = ["dict_from_dataclass", "dumps", "to_jsonable", "version_field"]


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


def _field_value(v: Any) -> Any:
    """A field value in its ``to_dict`` form: objects with ``to_dict()`` (or dataclasses)
    as dictionaries, tuples and lists as lists, mappings as dicts and arrays as nested
    lists, each element converted the same way; anything else as it is."""
    to_dict = getattr(v, "to_dict", None)
    if callable(to_dict):
        return to_dict()
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return dict_from_dataclass(v)
    if isinstance(v, (tuple, list)):
        return [_field_value(x) for x in v]
    if isinstance(v, Mapping):
        return {k: _field_value(x) for k, x in v.items()}
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def dict_from_dataclass(obj: Any, *, exclude: Collection[str] = (),
                        rename: Mapping[str, str] | None = None,
                        nan_to_none: Collection[str] = ()) -> dict[str, Any]:
    """The fields of the dataclass instance ``obj`` as a dictionary, in declaration order.

    Each value is converted as :func:`_field_value` says (nested results through their own
    ``to_dict()``, tuples as lists). The result is ready for :func:`dumps`.

    Args:
        exclude: fields left out.
        rename: field name -> JSON key, for the keys that differ from the field names.
        nan_to_none: float fields written as None when they are NaN.

    Raises:
        TypeError: ``obj`` is not a dataclass instance.
    """
    if not dataclasses.is_dataclass(obj) or isinstance(obj, type):
        raise TypeError(f"dict_from_dataclass: a {type(obj).__name__} is not a dataclass "
                        "instance")
    keys = rename or {}
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        if f.name in exclude:
            continue
        v = getattr(obj, f.name)
        if f.name in nan_to_none and isinstance(v, float) and math.isnan(v):
            out[keys.get(f.name, f.name)] = None
        else:
            out[keys.get(f.name, f.name)] = _field_value(v)
    return out


def version_field(doc: Mapping[str, Any], key: str, accepted: Collection[int], *, src: str,
                  error: type[ZRPError] = InputError, hint: str = "") -> int:
    """``doc[key]`` when it is an integer (not a boolean, not a float) among ``accepted``.

    Raises:
        error: naming ``src``, the field, its value and the accepted versions (``hint``
            appended: what to do).
    """
    v = doc.get(key)
    if type(v) is int and v in accepted:
        return v
    want = ", ".join(map(str, accepted))
    raise error(f"{src}: {key} {json.dumps(v) if _plain(v) else repr(v)}, expected "
                f"{'one of ' if len(accepted) > 1 else ''}{want} (an integer){hint}")


def _plain(v: Any) -> bool:
    return v is None or isinstance(v, (bool, int, float, str))
