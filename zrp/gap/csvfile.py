"""The measurement CSV file: strict reading (:func:`load_measurements`).

One row per measured point, rows in measurement order. Columns (header names, any order):

* ``pose`` (required): an id; all rows of a pose share the same joint values.
* ``point`` (optional): which target on the tool (e.g. one of several reflectors); default "p".
* ``q1`` .. ``qn`` (required): joint values, rad (deg with ``deg=True``) for revolute joints,
  the model's length unit for prismatic ones.
* ``x``, ``y``, ``z`` (required): measured position in the model's length unit, in the
  instrument's frame (or the robot's base frame with ``frame="base"``).
* ``qw``, ``qx``, ``qy``, ``qz`` (optional, all four): measured orientation (loaded and checked;
  the diagnosis uses positions only and says so with a warning).
* ``t`` (s), ``temp`` (deg C), ``load`` (kg) (optional).
* ``dir1`` .. ``dirn`` (optional, all n): the direction from which each joint approached the
  pose (-1, 0 or +1); when absent it is taken from the measurement order (see
  :meth:`~zrp.gap.data.Measurements.approach_direction`).

Lines starting with ``#`` are comments (skipped, with a warning after the header). Nothing is
dropped silently: an unknown column, a missing value, a non-number or a NaN is an error naming
the file, line and column. :meth:`~zrp.gap.data.Measurements.to_csv` writes this format.
"""

from __future__ import annotations

import csv
import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.data import FRAMES, OPTIONAL_SCALARS, QUAT_COLUMNS, DataWarning, Measurements
from zrp.model.manipulator import Manipulator

__all__ = ["load_measurements"]

F64 = NDArray[np.float64]
#: plausible temperatures, deg C.
TEMP_RANGE = (-60.0, 150.0)


@dataclass(frozen=True)
class _Header:
    """The checked header: column positions and which optional groups are present."""

    col: dict[str, int]
    qcols: list[str]
    dcols: list[str]
    scalars: list[str]
    quat: bool
    dirs: bool

    @property
    def n_fields(self) -> int:
        return len(self.col)


@dataclass(frozen=True)
class _Columns:
    """The parsed values, one entry per data row."""

    pose: NDArray
    point: NDArray
    q: F64
    xyz: F64
    scalars: dict[str, F64]
    quat: F64 | None
    dirs: F64 | None
    lines: NDArray[np.int64]


def _number(text: str, src: str, line: int, col: str) -> float:
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


def _split_lines(text: str, src: str, required: list[str]
                 ) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """The header and the data records (line number, fields); warns about comment lines."""
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    comments: list[int] = []
    for lineno, rec in enumerate(csv.reader(text.splitlines()), start=1):
        if not rec or all(not c.strip() for c in rec):
            continue
        if rec[0].lstrip().startswith("#"):
            if header is not None:
                comments.append(lineno)
            continue
        if header is None:
            header = [c.strip() for c in rec]
            continue
        rows.append((lineno, rec))
    if header is None:
        raise InputError(f"{src}: no header line, only comments; expected a header line with "
                         f"the columns {', '.join(required)}")
    if comments:
        shown = ", ".join(map(str, comments[:10])) + (" ..." if len(comments) > 10 else "")
        warnings.warn(f"{src}: {len(comments)} comment line(s) starting with # skipped (lines "
                      f"{shown})", DataWarning, stacklevel=3)
    return header, rows


def _check_header(header: list[str], src: str, model: Manipulator) -> _Header:
    n = model.n
    qcols = [f"q{k}" for k in range(1, n + 1)]
    dcols = [f"dir{k}" for k in range(1, n + 1)]
    required = ["pose", *qcols, "x", "y", "z"]
    allowed = [*required, "point", *QUAT_COLUMNS, *OPTIONAL_SCALARS, *dcols]
    dup = sorted({c for c in header if header.count(c) > 1})
    if dup:
        raise InputError(f"{src} line 1: column(s) {', '.join(dup)} appear more than once")
    unknown = [c for c in header if c not in allowed]
    if unknown:
        extra_q = [c for c in unknown if c.startswith("q") and c[1:].isdigit()]
        hint = (f" (the model {model.name!r} has {n} joints: q1..q{n})" if extra_q else "")
        raise InputError(f"{src} line 1: unknown column(s) {', '.join(unknown)}{hint}; valid "
                         f"columns are {', '.join(allowed)}")
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(f"{src} line 1: missing column(s) {', '.join(missing)}; required: "
                         f"{', '.join(required)} (q in rad, or deg with deg=True; x, y, z in "
                         f"{model.length_unit})")
    quat_given = [c for c in QUAT_COLUMNS if c in header]
    if quat_given and len(quat_given) != 4:
        raise InputError(f"{src} line 1: orientation needs all of qw, qx, qy, qz; got only "
                         f"{', '.join(quat_given)}")
    dir_given = [c for c in dcols if c in header]
    if dir_given and len(dir_given) != n:
        raise InputError(f"{src} line 1: approach directions need all of {', '.join(dcols)}; "
                         f"got only {', '.join(dir_given)}")
    col = {c: i for i, c in enumerate(header)}
    return _Header(col, qcols, dcols, [c for c in OPTIONAL_SCALARS if c in col],
                   bool(quat_given), bool(dir_given))


def _label(rec: list[str], i: int, name: str, what: str, src: str, lineno: int) -> str:
    text = rec[i].strip()
    if not text:
        raise InputError(f"{src} line {lineno}: column {name} is empty; expected {what}")
    return text


def _quaternion(rec: list[str], h: _Header, src: str, lineno: int) -> list[float]:
    quat = [_number(rec[h.col[c]], src, lineno, c) for c in QUAT_COLUMNS]
    nq = float(np.linalg.norm(quat))
    if abs(nq - 1.0) > 1e-3:
        raise InputError(f"{src} line {lineno}: orientation (qw, qx, qy, qz) has norm "
                         f"{nq:.6g}; expected a unit quaternion")
    return quat


def _direction(rec: list[str], h: _Header, src: str, lineno: int) -> list[float]:
    out = []
    for c in h.dcols:
        v = _number(rec[h.col[c]], src, lineno, c)
        if v not in (-1.0, 0.0, 1.0):
            raise InputError(f"{src} line {lineno}: column {c} is {v:g}; expected -1, 0 or +1")
        out.append(v)
    return out


def _parse(rows: list[tuple[int, list[str]]], h: _Header, header: list[str], src: str
           ) -> _Columns:
    r, n = len(rows), len(h.qcols)
    c = _Columns(np.empty(r, dtype=object), np.array(["p"] * r, dtype=object),
                 np.empty((r, n)), np.empty((r, 3)), {s: np.empty(r) for s in h.scalars},
                 np.empty((r, 4)) if h.quat else None, np.empty((r, n)) if h.dirs else None,
                 np.empty(r, dtype=np.int64))
    for i, (lineno, rec) in enumerate(rows):
        if len(rec) != h.n_fields:
            raise InputError(f"{src} line {lineno}: {len(rec)} fields, but the header has "
                             f"{h.n_fields} ({', '.join(header)})")
        c.lines[i] = lineno
        c.pose[i] = _label(rec, h.col["pose"], "pose", "an id", src, lineno)
        if "point" in h.col:
            c.point[i] = _label(rec, h.col["point"], "point", "a label", src, lineno)
        c.q[i] = [_number(rec[h.col[q]], src, lineno, q) for q in h.qcols]
        c.xyz[i] = [_number(rec[h.col[x]], src, lineno, x) for x in "xyz"]
        for name, arr in c.scalars.items():
            arr[i] = _number(rec[h.col[name]], src, lineno, name)
        if c.quat is not None:
            c.quat[i] = _quaternion(rec, h, src, lineno)
        if c.dirs is not None:
            c.dirs[i] = _direction(rec, h, src, lineno)
    return c


def _joint_units(q: F64, model: Manipulator, deg: bool, lines: NDArray[np.int64], src: str
                 ) -> None:
    """Revolute joint values to rad (in place) with ``deg``; else refuse values > 2 pi."""
    rev = ~np.asarray(model.prismatic)
    if deg:
        q[:, rev] = np.radians(q[:, rev])
        return
    big = np.abs(q[:, rev]) > 2.0 * math.pi + 1e-6
    if big.any():
        i, k = (int(v) for v in np.argwhere(big)[0])
        kk = int(np.flatnonzero(rev)[k])
        raise InputError(
            f"{src} line {lines[i]}: column q{kk + 1} is {q[i, kk]:g}, more than 2 pi rad: "
            "the joint values look like degrees; pass deg=True (--deg on the command line)")


def _check_scalars(scalars: dict[str, F64], lines: NDArray[np.int64], src: str) -> None:
    """Plausible temperatures (deg C) and non-negative loads (kg)."""
    if "temp" in scalars:
        tv = scalars["temp"]
        bad = (tv < TEMP_RANGE[0]) | (tv > TEMP_RANGE[1])
        if np.any(bad):
            i = int(np.argmax(bad))
            raise InputError(f"{src} line {lines[i]}: column temp is {tv[i]:g}; expected a "
                             "temperature in deg C (-60 to 150)")
    if "load" in scalars and np.any(scalars["load"] < 0.0):
        i = int(np.argmax(scalars["load"] < 0.0))
        raise InputError(f"{src} line {lines[i]}: column load is {scalars['load'][i]:g}; "
                         "expected a payload mass in kg >= 0")


def load_measurements(path: str | os.PathLike[str], model: Manipulator, *, deg: bool = False,
                      frame: str = "instrument") -> Measurements:
    """Read a measurement CSV (format in the module docstring) strictly.

    Args:
        path: the CSV file.
        model: the robot model (gives n, the joint types and the length unit).
        deg: revolute joint values (and nothing else) are in degrees.
        frame: "instrument" (positions in an unknown instrument frame) or "base".

    Raises:
        InputError: naming the file, line and column of the first problem.
    """
    path = Path(path)
    src = str(path)
    if frame not in FRAMES:
        raise InputError(f"frame: {frame!r} is not a frame; expected one of {FRAMES}")
    if not path.is_file():
        raise InputError(f"{src}: no such file")
    with open(path, newline="", encoding="utf-8-sig") as fh:
        text = fh.read()
    required = ["pose", *[f"q{k}" for k in range(1, model.n + 1)], "x", "y", "z"]
    if not text.strip():
        raise InputError(f"{src}: the file is empty; expected a header line with the columns "
                         f"{', '.join(required)} (optional: point, t, temp, load, qw..qz, dir1..)")
    header, rows = _split_lines(text, src, required)
    h = _check_header(header, src, model)
    if not rows:
        raise InputError(f"{src}: no data rows after the header; expected one row per "
                         "measured point")
    c = _parse(rows, h, header, src)
    _joint_units(c.q, model, deg, c.lines, src)
    _check_scalars(c.scalars, c.lines, src)
    if c.quat is not None:
        warnings.warn(f"{src}: measured orientations (qw..qz) are loaded but the diagnosis uses "
                      "positions only", DataWarning, stacklevel=2)
    return Measurements(c.pose, c.point, c.q, c.xyz, frame, c.scalars.get("t"),
                        c.scalars.get("temp"), c.scalars.get("load"), c.quat, c.dirs, c.lines,
                        src)
