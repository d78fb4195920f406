"""The measurement CSV's header and records (format in :mod:`zrp.gap.data.csvfile`): the
header checked against the model, each record checked field by field and appended to compact
arrays.
"""

from __future__ import annotations

import math
from array import array
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.escape import csv_uncell
from zrp.gap.data.measurements import OPTIONAL_SCALARS, QUAT_COLUMNS
from zrp.model.manipulator import Manipulator
from zrp.units import split_unit

__all__ = ["Accumulator", "Columns", "Header", "check_header", "number_cell", "parse_row"]



@dataclass(frozen=True)
class Header:
    """The checked header: column positions and which optional groups are present."""

    col: dict[str, int]
    qcols: list[str]
    dcols: list[str]
    scalars: list[str]
    quat: bool
    dirs: bool
    #: the unit each column declares (``q1[deg]``, ``x[mm]``), None where it declares none
    units: dict[str, str | None]

    @property
    def n_fields(self) -> int:
        return len(self.col)


@dataclass(frozen=True)
class Columns:
    """The parsed values, one entry per data row."""

    pose: NDArray
    point: NDArray
    q: F64
    xyz: F64
    scalars: dict[str, F64]
    quat: F64 | None
    dirs: F64 | None
    lines: NDArray[np.int64]


def number_cell(text: str, src: str, line: int, col: str) -> float:
    """The finite number in a CSV cell, or an error naming the file, line and column."""
    s = text.strip()
    if s == "":
        raise InputError(f"{src} line {line}: column {col} is empty; expected a number")
    try:
        v = float(s)
    except ValueError:
        raise InputError(f"{src} line {line}: column {col} is {s!r}; expected a number") from None
    if not math.isfinite(v):
        raise InputError(f"{src} line {line}: column {col} is {s!r}; expected a finite number")
    return v


def _check_names(header: list[str], src: str, model: Manipulator, required: list[str],
                 allowed: list[str]) -> None:
    """No column twice, none unknown, none of ``required`` missing."""
    dup = sorted({c for c in header if header.count(c) > 1})
    if dup:
        raise InputError(f"{src} line 1: column(s) {', '.join(dup)} appear more than once")
    unknown = [c for c in header if c not in allowed]
    if unknown:
        extra_q = [c for c in unknown if c.startswith("q") and c[1:].isdigit()]
        hint = (f" (the model {model.name!r} has {model.n} joints: q1..q{model.n})" if extra_q
                else "")
        raise InputError(f"{src} line 1: unknown column(s) {', '.join(unknown)}{hint}; valid "
                         f"columns are {', '.join(allowed)}")
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(f"{src} line 1: missing column(s) {', '.join(missing)}; required: "
                         f"{', '.join(required)} (q in rad, or deg with deg=True; x, y, z in "
                         f"{model.length_unit})")


def _complete_group(header: list[str], src: str, group: list[str], what: str) -> bool:
    """Whether the columns of ``group`` are given: all of them or none."""
    given = [c for c in header if c in group]
    if given and len(given) != len(group):
        raise InputError(f"{src} line 1: {what} all of {', '.join(group)}; got only "
                         f"{', '.join(c for c in group if c in given)}")
    return bool(given)


def check_header(header: list[str], src: str, model: Manipulator) -> Header:
    """The header checked: names (each may declare its unit, ``q1[deg]``; zrp.units)."""
    parsed = [split_unit(c, f"{src} line 1") for c in header]
    header = [name for name, _ in parsed]
    declared = dict(parsed)
    for c, u in parsed:
        if u is not None and not (c in "xyz" or (c.startswith("q") and c[1:].isdigit())):
            raise InputError(f"{src} line 1: column {c}[{u}]: only joint (q1..) and position "
                             "(x, y, z) columns take a unit")
    n = model.n
    qcols = [f"q{k}" for k in range(1, n + 1)]
    dcols = [f"dir{k}" for k in range(1, n + 1)]
    required = ["pose", *qcols, "x", "y", "z"]
    _check_names(header, src, model, required,
                 [*required, "point", *QUAT_COLUMNS, *OPTIONAL_SCALARS, *dcols])
    quat = _complete_group(header, src, list(QUAT_COLUMNS), "orientation needs")
    dirs = _complete_group(header, src, dcols, "approach directions need")
    col = {c: i for i, c in enumerate(header)}
    return Header(col, qcols, dcols, [c for c in OPTIONAL_SCALARS if c in col], quat, dirs,
                  declared)


def _label(rec: list[str], i: int, name: str, what: str, src: str, lineno: int) -> str:
    text = csv_uncell(rec[i].strip())
    if not text:
        raise InputError(f"{src} line {lineno}: column {name} is empty; expected {what}")
    return text


def _quaternion(rec: list[str], h: Header, src: str, lineno: int) -> list[float]:
    quat = [number_cell(rec[h.col[c]], src, lineno, c) for c in QUAT_COLUMNS]
    nq = float(np.linalg.norm(quat))
    if abs(nq - 1.0) > 1e-3:
        raise InputError(f"{src} line {lineno}: orientation (qw, qx, qy, qz) has norm "
                         f"{nq:.6g}; expected a unit quaternion")
    return quat


def _direction(rec: list[str], h: Header, src: str, lineno: int) -> list[float]:
    out = []
    for c in h.dcols:
        v = number_cell(rec[h.col[c]], src, lineno, c)
        if v not in (-1.0, 0.0, 1.0):
            raise InputError(f"{src} line {lineno}: column {c} is {v:g}; expected -1, 0 or +1")
        out.append(v)
    return out


def parse_row(c: Accumulator, lineno: int, rec: list[str], h: Header, header: list[str],
               src: str) -> None:
    """Check one data record and append its values to ``c``."""
    if len(rec) != h.n_fields:
        raise InputError(f"{src} line {lineno}: {len(rec)} fields, but the header has "
                         f"{h.n_fields} ({', '.join(header)})")
    c.lines.append(lineno)
    c.pose.append(_label(rec, h.col["pose"], "pose", "an id", src, lineno))
    if "point" in h.col:
        label = _label(rec, h.col["point"], "point", "a label", src, lineno)
        c.point.append(c.labels.setdefault(label, label))  # one string object per label
    c.q.extend([number_cell(rec[h.col[q]], src, lineno, q) for q in h.qcols])
    c.xyz.extend([number_cell(rec[h.col[x]], src, lineno, x) for x in "xyz"])
    for name in h.scalars:
        c.scalars[name].append(number_cell(rec[h.col[name]], src, lineno, name))
    if h.quat:
        c.quat.extend(_quaternion(rec, h, src, lineno))
    if h.dirs:
        c.dirs.extend(_direction(rec, h, src, lineno))


class Accumulator:
    """Parsed values, appended row by row into compact arrays (8 bytes a number), so that a
    file of millions of rows is read in one pass with memory linear in its numbers."""

    def __init__(self, h: Header) -> None:
        self.pose: list[str] = []
        self.point: list[str] = []
        self.labels: dict[str, str] = {}
        self.q, self.xyz, self.quat, self.dirs = (array("d") for _ in range(4))
        self.scalars = {name: array("d") for name in h.scalars}
        self.lines = array("q")

    def columns(self, h: Header) -> Columns:
        r, n = len(self.lines), len(h.qcols)

        def mat(a: array, width: int) -> F64:
            return np.frombuffer(a, dtype=float).reshape(r, width).copy()

        point = (np.array(self.point, dtype=object) if self.point
                 else np.full(r, "p", dtype=object))
        return Columns(np.array(self.pose, dtype=object), point, mat(self.q, n),
                        mat(self.xyz, 3),
                        {k: np.frombuffer(v, dtype=float).copy() for k, v in self.scalars.items()},
                        mat(self.quat, 4) if h.quat else None,
                        mat(self.dirs, n) if h.dirs else None,
                        np.frombuffer(self.lines, dtype=np.int64).copy())
