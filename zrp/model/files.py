"""Read and write manipulator models as TOML files (layout documented in README.md).

```toml
name = "PUMA-type manipulator (paper, Table 1)"
length_unit = "mm"
[[joint]]            # one table per joint, base to tip
type = "revolute"    # or "prismatic"
axis = [0, 0, 1]     # u_{k,0}
body = [0, 0, 0]     # b_{k,0}
[end_effector]
body = [0, 0, -127]       # b_{n+1,0}
axial = [0, 0, -1]        # u_{a,0}
transverse = [0, -1, 0]   # u_{t,0}
```
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from zrp.errors import InputError, ModelError, ModelFileError
from zrp.model.builtin import builtin_models
from zrp.model.manipulator import EndEffector, Joint, Manipulator
from zrp.output import write_text
from zrp.textio import read_text
from zrp.units import canonical_length_unit

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["builtin_models", "dumps_model", "load_model", "loads_model", "save_model"]

_TOP_KEYS = {"name", "length_unit", "joint", "end_effector"}
_JOINT_KEYS = {"type", "axis", "body", "name", "limits", "velocity_limit"}
_EE_KEYS = {"body", "axial", "transverse"}


class _Lines:
    """The lines of a model file, indexed once, so that finding the line of each joint's table
    and key costs time linear in the file (the parser stays linear in the joint count)."""

    def __init__(self, text: str) -> None:
        self.lines = [line.strip() for line in text.split("\n")]
        self._tables: dict[str, list[int]] = {}

    def first(self, pattern: str) -> int | None:
        """1-based line number of the first line matching ``pattern`` (a regex)."""
        rx = re.compile(pattern)
        return next((i for i, line in enumerate(self.lines, start=1) if rx.match(line)), None)

    def table(self, pattern: str, occurrence: int) -> int | None:
        """1-based line of the ``occurrence``-th table header matching ``pattern``."""
        if pattern not in self._tables:
            rx = re.compile(pattern)
            self._tables[pattern] = [i for i, line in enumerate(self.lines, start=1)
                                     if line.startswith("[") and rx.match(line)]
        hits = self._tables[pattern]
        return hits[occurrence] if 0 <= occurrence < len(hits) else None

    def key(self, table_line: int | None, key: str) -> int | None:
        """Line of ``key = ...`` inside the table that starts at ``table_line``."""
        if table_line is None:
            return None
        rx = re.compile(rf"{re.escape(key)}\s*=")
        for i in range(table_line, len(self.lines)):
            s = self.lines[i]
            if s.startswith("[") and i + 1 != table_line:
                return None
            if rx.match(s):
                return i + 1
        return None


def loads_model(text: str, source: str = "<string>") -> Manipulator:
    """Parse a model from TOML text. Errors name ``source`` and the line at fault."""
    if not isinstance(text, str):
        raise ModelFileError(f"text: expected the TOML text as a str, got {type(text).__name__}")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{source}: not valid TOML: {exc}") from exc
    return _from_dict(data, text, source)


def load_model(path: str | Path) -> Manipulator:
    """Read a model file. ``path`` may also name a built-in model (see :func:`builtin_models`)."""
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)) \
            or not str(path).strip():
        raise ModelFileError(f"path: expected a model file name or a built-in model "
                             f"{sorted(builtin_models())}, got {path!r}")
    p = Path(path)
    try:
        present = p.exists()
    except OSError as exc:  # e.g. a name over the file system's limit (ENAMETOOLONG)
        raise ModelFileError(f"{str(path)[:80]}{'...' if len(str(path)) > 80 else ''}: not a "
                             f"usable file name ({exc.strerror or exc})") from None
    if not present:
        builtins = builtin_models()
        if str(path) in builtins:
            p = builtins[str(path)]
        else:
            raise ModelFileError(
                f"{path}: no such model file; built-in models are {sorted(builtins)}"
            )
    text = read_text(p, error=ModelFileError)  # a regular file, size checked, UTF-8/16
    return loads_model(text, str(p))


def _check_top(data: dict[str, Any], lines: _Lines,
               fail: Callable[[str, int | None], ModelFileError]) -> str:
    """The top-level tables and values: [[joint]] tables, [end_effector], name, length_unit.
    Returns the length unit."""
    joints_raw = data.get("joint")
    if not isinstance(joints_raw, list) or not joints_raw \
            or not all(isinstance(j, dict) for j in joints_raw):
        raise fail("joint: no [[joint]] tables (keys type, axis, body, name); a model needs "
                   "at least one joint", lines.first(r"joint\s*="))
    if "end_effector" not in data or not isinstance(data["end_effector"], dict):
        raise fail("missing [end_effector] table (keys body, axial, transverse)", None)
    if not isinstance(data.get("name", ""), str):
        raise fail(f"name: expected a string, got {data['name']!r}", lines.first(r"name\s*="))
    unit = data.get("length_unit", "mm")
    if not isinstance(unit, str) or not unit:
        raise fail(f"length_unit: expected a string such as \"mm\", got {unit!r}",
                   lines.first(r"length_unit\s*="))
    try:
        canonical_length_unit(unit)
    except InputError as exc:
        raise fail(str(exc), lines.first(r"length_unit\s*=")) from exc
    return unit


def _from_dict(data: dict[str, Any], text: str, source: str) -> Manipulator:
    lines = _Lines(text)
    _line_of = lines.first
    _key_line = lines.key

    def fail(msg: str, line: int | None) -> ModelFileError:
        where = f"{source}, line {line}" if line else source
        return ModelFileError(f"{where}: {msg}")

    unknown = set(data) - _TOP_KEYS
    if unknown:
        key = sorted(unknown)[0]
        raise fail(f"unknown key {key!r}; expected one of {sorted(_TOP_KEYS)}",
                   _line_of(rf"{re.escape(key)}\s*="))
    joints_raw = data.get("joint")
    unit = _check_top(data, lines, fail)

    def check_table(label: str, table: dict[str, Any], allowed: set[str],
                    required: tuple[str, ...], tline: int | None) -> None:
        bad = set(table) - allowed
        if bad:
            key = sorted(bad)[0]
            raise fail(f"{label}: unknown key {key!r}; expected one of {sorted(allowed)}",
                       _key_line(tline, key) or tline)
        for key in required:
            if key not in table:
                raise fail(f"{label}: missing {key!r}", tline)

    def line_of_error(exc: ModelError, fields: tuple[str, ...], tline: int | None) -> int | None:
        """The line of the field a validation message names (its text before the colon)."""
        head = str(exc).split(":")[0]
        field = next((f for f in fields if f in head), None)
        return (_key_line(tline, field) if field else None) or tline

    joint_fields = ("type", "axis", "body", "velocity_limit", "limits")
    joints = []
    for k, jd in enumerate(joints_raw, start=1):
        tline = lines.table(r"\[\[\s*joint\s*\]\]", k - 1)
        check_table(f"joint {k}", jd, _JOINT_KEYS, joint_fields[:3], tline)
        if not isinstance(jd.get("name", ""), str):
            raise fail(f"joint {k} name: expected a string, got {jd['name']!r}",
                       _key_line(tline, "name") or tline)
        try:
            joints.append(Joint(type=jd["type"], axis=jd["axis"], body=jd["body"],
                                name=str(jd.get("name", "")), index=k,
                                limits=jd.get("limits"), velocity_limit=jd.get("velocity_limit")))
        except ModelError as exc:
            raise fail(str(exc), line_of_error(exc, joint_fields, tline)) from exc

    ed = data["end_effector"]
    eline = _line_of(r"\[\s*end_effector\s*\]")
    ee_fields = ("axial", "transverse", "body")
    check_table("end_effector", ed, _EE_KEYS, ee_fields, eline)
    try:
        ee = EndEffector(body=ed["body"], axial=ed["axial"], transverse=ed["transverse"])
    except ModelError as exc:
        raise fail(str(exc), line_of_error(exc, ee_fields, eline)) from exc
    return Manipulator(tuple(joints), ee, name=str(data.get("name", Path(source).stem)),
                       length_unit=unit)


def _fmt_vec(v: np.ndarray) -> str:
    return "[" + ", ".join(repr(float(x)) if x != int(x) else str(int(x)) for x in v) + "]"


def dumps_model(model: Manipulator) -> str:
    """The model as TOML text in the documented layout (floats written with full precision)."""
    out = [f"name = {_toml_str(model.name)}", f"length_unit = {_toml_str(model.length_unit)}", ""]
    for j in model.joints:
        out.append("[[joint]]")
        if j.name:
            out.append(f"name = {_toml_str(j.name)}")
        out += [f'type = "{j.type}"', f"axis = {_fmt_vec(j.axis)}", f"body = {_fmt_vec(j.body)}"]
        if j.limits is not None:  # optional; rad or the length unit (prismatic)
            out.append(f"limits = [{j.limits[0]!r}, {j.limits[1]!r}]")  # inf is valid TOML
        if j.velocity_limit is not None:
            out.append(f"velocity_limit = {j.velocity_limit!r}")
        out.append("")
    ee = model.end_effector
    out += ["[end_effector]", f"body = {_fmt_vec(ee.body)}", f"axial = {_fmt_vec(ee.axial)}",
            f"transverse = {_fmt_vec(ee.transverse)}", ""]
    return "\n".join(out)


def _toml_str(s: str) -> str:
    """A TOML basic string: backslash, quote and every control character escaped."""
    out = []
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def save_model(model: Manipulator, path: str | Path, *, overwrite: bool = False) -> Path:
    """Write ``model`` to ``path`` atomically (:mod:`zrp.output`).

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
    """
    return write_text(path, dumps_model(model), overwrite=overwrite)


