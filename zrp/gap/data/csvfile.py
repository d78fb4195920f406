"""The measurement CSV file: strict reading (:func:`load_measurements`).

One row per measured point, rows in measurement order. Columns (header names, any order):

* ``pose`` (required): an id; all rows of a pose share the same joint values.
* ``point`` (optional): which target on the tool (e.g. one of several reflectors); default "p".
* ``q1`` .. ``qn`` (required): joint values, rad (deg with ``deg=True``) for revolute joints,
  the model's length unit for prismatic ones.
* ``x``, ``y``, ``z`` (required): measured position in the model's length unit, in the
  instrument's frame (or the robot's base frame with ``frame="base"``).
* ``qw``, ``qx``, ``qy``, ``qz`` (optional, all four): measured orientation (loaded and checked;
  the diagnosis chooses effects from positions only and says so with a warning; zrp calibrate
  and zrp.gap.fit.fullpose use them).
* ``t`` (s), ``temp`` (deg C), ``load`` (kg) (optional).
* ``dir1`` .. ``dirn`` (optional, all n): the direction from which each joint approached the
  pose (-1, 0 or +1); when absent it is taken from the measurement order (see
  :meth:`~zrp.gap.data.measurements.Measurements.approach_direction`).

Lines starting with ``#`` are comments (skipped, with a warning after the header). Nothing is
dropped silently: an unknown column, a missing value, a non-number or a NaN is an error naming
the file, line and column. :meth:`~zrp.gap.data.measurements.Measurements.to_csv` writes this
format.

The file is read in one pass, record by record, into compact arrays (memory about 8 bytes a
number plus the pose ids), as UTF-8 (with or without a byte-order mark) or UTF-16 with its
byte-order mark; a byte that does not decode, or a field longer than
``csv.field_size_limit()`` (131,072 characters), is an error naming its line. Only CR/LF end a
record: a form feed or U+2028 inside a quoted field stays in the field.
"""

from __future__ import annotations

import csv
import math
import os
import warnings
from array import array
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from zrp.arguments import check_int
from zrp.errors import InputError
from zrp.gap.data.measurements import (
    FRAMES,
    OPTIONAL_SCALARS,
    QUAT_COLUMNS,
    DataWarning,
    Measurements,
)
from zrp.model.manipulator import Manipulator

__all__ = ["MAX_ROWS", "load_measurements"]

#: Most data rows read by default: about 0.7 GB of memory per million rows at the peak of a
#: whole diagnosis, so two million stay within 2 GB.
MAX_ROWS = 2_000_000

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


def _parse_row(c: _Accumulator, lineno: int, rec: list[str], h: _Header, header: list[str],
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
    c.q.extend([_number(rec[h.col[q]], src, lineno, q) for q in h.qcols])
    c.xyz.extend([_number(rec[h.col[x]], src, lineno, x) for x in "xyz"])
    for name in h.scalars:
        c.scalars[name].append(_number(rec[h.col[name]], src, lineno, name))
    if h.quat:
        c.quat.extend(_quaternion(rec, h, src, lineno))
    if h.dirs:
        c.dirs.extend(_direction(rec, h, src, lineno))


class _Accumulator:
    """Parsed values, appended row by row into compact arrays (8 bytes a number), so that a
    file of millions of rows is read in one pass with memory linear in its numbers."""

    def __init__(self, h: _Header) -> None:
        self.pose: list[str] = []
        self.point: list[str] = []
        self.labels: dict[str, str] = {}
        self.q, self.xyz, self.quat, self.dirs = (array("d") for _ in range(4))
        self.scalars = {name: array("d") for name in h.scalars}
        self.lines = array("q")

    def columns(self, h: _Header) -> _Columns:
        r, n = len(self.lines), len(h.qcols)

        def mat(a: array, width: int) -> F64:
            return np.frombuffer(a, dtype=float).reshape(r, width).copy()

        point = (np.array(self.point, dtype=object) if self.point
                 else np.full(r, "p", dtype=object))
        return _Columns(np.array(self.pose, dtype=object), point, mat(self.q, n),
                        mat(self.xyz, 3),
                        {k: np.frombuffer(v, dtype=float).copy() for k, v in self.scalars.items()},
                        mat(self.quat, 4) if h.quat else None,
                        mat(self.dirs, n) if h.dirs else None,
                        np.frombuffer(self.lines, dtype=np.int64).copy())


def _encoding(path: Path) -> str:
    """UTF-16 when the file starts with its byte-order mark, else UTF-8 (with or without BOM)."""
    with open(path, "rb") as fh:
        head = fh.read(2)
    return "utf-16" if head in (b"\xff\xfe", b"\xfe\xff") else "utf-8-sig"


def _records(fh: Iterable[str], src: str) -> Iterator[tuple[int, list[str]]]:
    """(first line number, fields) of each record of a CSV text stream; a decoding error or an
    over-long field is an :class:`InputError` naming the line."""
    reader = csv.reader(fh)
    last = 0
    while True:
        try:
            rec = next(reader)
        except StopIteration:
            return
        except UnicodeDecodeError as exc:
            line = _undecodable_line(src) or reader.line_num + 1
            raise InputError(
                f"{src} line {line}: byte 0x{exc.object[exc.start]:02x} is not "
                f"{exc.encoding.upper()} text; save the file as UTF-8 (or UTF-16 with a "
                "byte-order mark)") from None
        except csv.Error as exc:
            raise InputError(f"{src} line {last + 1}: {exc} (at most "
                             f"{csv.field_size_limit()} characters a field); expected a "
                             "measurement CSV") from None
        yield last + 1, rec
        last = reader.line_num


def _undecodable_line(src: str) -> int | None:
    """The first line of a UTF-8 file that does not decode (read again, only after an error)."""
    with open(src, "rb") as fh:
        for lineno, raw in enumerate(fh, start=1):
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError:
                return lineno
    return None


def _read(path: Path, src: str, model: Manipulator, progress: bool, max_rows: int | None
          ) -> tuple[list[str], _Header, _Columns]:
    """Stream the file once: the header, then each data row checked and appended."""
    required = ["pose", *[f"q{k}" for k in range(1, model.n + 1)], "x", "y", "z"]
    header: list[str] | None = None
    h: _Header | None = None
    acc: _Accumulator | None = None
    comments: list[int] = []
    seen_text = False
    bar = tqdm(desc=f"reading {path.name}", unit=" rows", disable=not progress,
               mininterval=1.0, leave=False)
    with open(path, newline="", encoding=_encoding(path)) as fh, bar:
        for lineno, rec in _records(fh, src):
            if not rec or all(not c.strip() for c in rec):
                seen_text = seen_text or bool(rec)
                continue
            seen_text = True
            if rec[0].lstrip().startswith("#"):
                if header is not None:
                    comments.append(lineno)
                continue
            if header is None:
                header = [c.strip() for c in rec]
                h = _check_header(header, src, model)
                acc = _Accumulator(h)
                continue
            if max_rows is not None and len(acc.lines) >= max_rows:  # type: ignore[union-attr]
                raise InputError(
                    f"{src} line {lineno}: more than max_rows={max_rows} data rows (about 0.7 GB "
                    "of memory per million rows); split the file or thin it (every k-th pose), "
                    "or pass a larger max_rows (--max-rows on the command line)")
            _parse_row(acc, lineno, rec, h, header, src)  # type: ignore[arg-type]
            if len(acc.lines) % 10000 == 0:  # type: ignore[union-attr]
                bar.update(10000)
    if header is None or h is None or acc is None:
        if not seen_text:
            raise InputError(f"{src}: the file is empty; expected a header line with the "
                             f"columns {', '.join(required)} (optional: point, t, temp, load, "
                             "qw..qz, dir1..)")
        raise InputError(f"{src}: no header line (only comments or empty fields); expected a "
                         f"header line with the columns {', '.join(required)}")
    if comments:
        shown = ", ".join(map(str, comments[:10])) + (" ..." if len(comments) > 10 else "")
        warnings.warn(f"{src}: {len(comments)} comment line(s) starting with # skipped (lines "
                      f"{shown})", DataWarning, stacklevel=3)
    if not acc.lines:
        raise InputError(f"{src}: no data rows after the header; expected one row per "
                         "measured point")
    return header, h, acc.columns(h)


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
                      frame: str = "instrument", progress: bool = False,
                      max_rows: int | None = MAX_ROWS) -> Measurements:
    """Read a measurement CSV (format in the module docstring) strictly.

    Args:
        path: the CSV file.
        model: the robot model (gives n, the joint types and the length unit).
        deg: revolute joint values (and nothing else) are in degrees.
        frame: "instrument" (positions in an unknown instrument frame) or "base".
        progress: show a progress bar (rows read) on stderr.
        max_rows: most data rows read (:data:`MAX_ROWS`; None: no limit): a larger file is
            refused at the first row beyond it, before memory runs out.

    The file is read in one pass, row by row (memory about 8 bytes per number plus the pose
    ids), UTF-8 or UTF-16 with a byte-order mark.

    Raises:
        InputError: naming the file, line and column of the first problem.
    """
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a CSV file name, got {type(path).__name__}")
    if not isinstance(model, Manipulator):
        raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
    path = Path(path)
    src = str(path)
    if frame not in FRAMES:
        raise InputError(f"frame: {frame!r} is not a frame; expected one of {FRAMES}")
    if not path.is_file():
        raise InputError(f"{src}: no such file")
    try:
        _, _, c = _read(path, src, model, progress,
                        None if max_rows is None else check_int(max_rows, "max_rows", 1))
    except OSError as exc:
        raise InputError(f"{src}: cannot read ({exc.strerror or exc})") from exc
    _joint_units(c.q, model, deg, c.lines, src)
    _check_scalars(c.scalars, c.lines, src)
    if c.quat is not None:
        warnings.warn(f"{src}: measured orientations (qw..qz) are loaded; the diagnosis chooses "
                      "the effects from the positions, then refits its final model with the "
                      "orientations and adds effects only they reveal (the report's full-pose "
                      "section; use_orientation=False / --no-orientation: positions only)",
                      DataWarning, stacklevel=2)
    return Measurements(c.pose, c.point, c.q, c.xyz, frame, c.scalars.get("t"),
                        c.scalars.get("temp"), c.scalars.get("load"), c.quat, c.dirs, c.lines,
                        src)
