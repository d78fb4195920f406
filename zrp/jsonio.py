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

:func:`read_json` is the one way a user's JSON file is read (diagnosis.json,
compensation.json, a fleet's stored diagnoses): a regular file whose size is checked before
a byte is parsed (``max_bytes``, named in the error: :data:`MAX_DIAGNOSIS_BYTES`,
:data:`MAX_COMPENSATION_BYTES`), arrays and objects nested at most :data:`MAX_JSON_DEPTH`
deep (counted in chunks: memory a small multiple of the text, whatever it holds), and
``NaN``/``Infinity`` refused (the files hold finite numbers only; ``1e999`` reads as
infinity, which each reader's domain checks refuse by field). :func:`loads_json` is the same
for a text already read.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
from collections.abc import Collection, Mapping
from pathlib import PurePath
from typing import Any

import numpy as np

from zrp.errors import InputError, ZRPError
from zrp.textio import read_text

__all__ = ["MAX_COMPENSATION_BYTES", "MAX_DIAGNOSIS_BYTES", "MAX_JSON_DEPTH",
           "dict_from_dataclass", "dumps", "json_depth", "loads_json", "read_json",
           "to_jsonable", "version_field"]

#: deepest nesting of arrays and objects a file of this toolkit may hold
MAX_JSON_DEPTH = 32
#: largest diagnosis.json read: 50 MiB (a diagnosis of 100,000 points is ~15 MB)
MAX_DIAGNOSIS_BYTES = 50 * 2**20
#: largest compensation.json read: 20 MiB (a learned term of 5,000 poses is ~3 MB)
MAX_COMPENSATION_BYTES = 20 * 2**20
#: characters scanned at a time by :func:`json_depth`
_SCAN_CHUNK = 2**20
#: a JSON string (its brackets do not nest)
_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.S)
_OPEN = str.maketrans({"[": "\x01", "{": "\x01", "]": "\x02", "}": "\x02"})


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


def json_depth(text: str) -> int:
    """The deepest nesting of arrays and objects in the JSON ``text`` (brackets inside
    strings do not count), counted a chunk at a time: the memory it takes is one copy of the
    text with its strings emptied plus a few times :data:`_SCAN_CHUNK`, not eight bytes a
    character (an unterminated string is left to the parser)."""
    bare = _STRING.sub('""', text)
    depth = best = 0
    for a in range(0, len(bare), _SCAN_CHUNK):
        raw = np.frombuffer(bare[a:a + _SCAN_CHUNK].translate(_OPEN).encode(
            "utf-8", "replace"), dtype=np.uint8)
        run = np.cumsum((raw == 1).astype(np.int32) - (raw == 2).astype(np.int32),
                        dtype=np.int64)
        best = max(best, depth + int(run.max()))
        depth += int(run[-1])
    return best


def loads_json(text: str, src: str, *, what: str = "file") -> Any:
    """``json.loads(text)`` after checking its nesting (:data:`MAX_JSON_DEPTH`); ``NaN``
    and ``Infinity`` refused.

    Raises:
        InputError: too deep or not JSON, naming ``src`` (``what``: what the file is, e.g.
            "diagnosis.json").
    """
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise InputError(f"{src}: JSON nested {depth} deep; a {what} nests at most "
                         f"{MAX_JSON_DEPTH} deep")
    try:
        return json.loads(text, parse_constant=_no_constant)
    except (ValueError, RecursionError) as exc:
        raise InputError(f"{src}: cannot read the {what}: {exc}") from None


def read_json(path: str | os.PathLike[str], *, max_bytes: int, label: str | None = None,
              what: str = "file") -> Any:
    """The JSON document of a user's file: a regular file of at most ``max_bytes`` (checked
    before it is read), then :func:`loads_json`.

    Raises:
        InputError: not a regular file, larger than ``max_bytes`` (naming the limit), not
            UTF-8, too deep or not JSON (naming the file).
    """
    src = str(path) if label is None else label
    try:
        text = read_text(path, label=src, max_bytes=max_bytes)
    except InputError as exc:
        if "more than the" in str(exc):
            raise InputError(f"{exc} (a {what} holds at most {max_bytes // 2**20} MiB)"
                             ) from None
        raise
    return loads_json(text, src, what=what)


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not a JSON number (the files hold finite numbers only)")
