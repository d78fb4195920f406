"""The measurement CSV file: strict reading (:func:`load_measurements`).

One row per measured point, rows in measurement order. Columns (header names, any order):

* ``pose`` (required): an id; all rows of a pose share the same joint values.
* ``point`` (optional): which target on the tool (e.g. one of several reflectors); default "p".
* ``q1`` .. ``qn`` (required): joint values, rad (deg with ``deg=True``) for revolute joints,
  the model's length unit for prismatic ones, unless the header declares the unit
  (``q1[deg]``, ``q3[mm]``: the rule of :mod:`zrp.units`, checked there).
* ``x``, ``y``, ``z`` (required): measured position in the model's length unit (or the unit
  the header declares, ``x[m]``), in the instrument's frame (or the robot's base frame with
  ``frame="base"``).
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
import os
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from zrp.arguments import check_int
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.csvrows import Accumulator, Columns, Header, check_header, parse_row
from zrp.gap.data.measurements import FRAMES, DataWarning, Measurements
from zrp.model.manipulator import Manipulator
from zrp.units import angle_bounds, joint_column_units, joint_values_to_rad, length_scale

__all__ = ["MAX_ROWS", "load_measurements"]

#: Most data rows read by default: about 0.7 GB of memory per million rows at the peak of a
#: whole diagnosis, so two million stay within 2 GB.
MAX_ROWS = 2_000_000

#: plausible temperatures, deg C.
TEMP_RANGE = (-60.0, 150.0)


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


class _Reader:
    """One pass over the records: comments and blank records skipped, the header checked, then
    each data row checked and appended."""

    def __init__(self, src: str, model: Manipulator, max_rows: int | None) -> None:
        self.src, self.model, self.max_rows = src, model, max_rows
        self.header: list[str] | None = None
        self.h: Header | None = None
        self.acc: Accumulator | None = None
        self.comments: list[int] = []
        self.seen_text = False

    def feed(self, lineno: int, rec: list[str]) -> bool:
        """Take one record; True when it was a data row (appended)."""
        if not rec or all(not c.strip() for c in rec):
            self.seen_text = self.seen_text or bool(rec)
            return False
        self.seen_text = True
        if rec[0].lstrip().startswith("#"):
            if self.header is not None:
                self.comments.append(lineno)
            return False
        if self.header is None or self.h is None or self.acc is None:
            self.header = [c.strip() for c in rec]
            self.h = check_header(self.header, self.src, self.model)
            self.acc = Accumulator(self.h)
            return False
        if self.max_rows is not None and len(self.acc.lines) >= self.max_rows:
            raise InputError(
                f"{self.src} line {lineno}: more than max_rows={self.max_rows} data rows (about "
                "0.7 GB of memory per million rows); split the file or thin it (every k-th "
                "pose), or pass a larger max_rows (--max-rows on the command line)")
        parse_row(self.acc, lineno, rec, self.h, self.header, self.src)
        return True

    @property
    def rows(self) -> int:
        """Data rows appended so far."""
        return 0 if self.acc is None else len(self.acc.lines)

    def parsed(self) -> tuple[list[str], Header, Accumulator]:
        """The header and the rows, once the file has a header line."""
        if self.header is None or self.h is None or self.acc is None:
            required = ", ".join(["pose", *[f"q{k}" for k in range(1, self.model.n + 1)],
                                  "x", "y", "z"])
            if not self.seen_text:
                raise InputError(f"{self.src}: the file is empty; expected a header line with "
                                 f"the columns {required} (optional: point, t, temp, load, "
                                 "qw..qz, dir1..)")
            raise InputError(f"{self.src}: no header line (only comments or empty fields); "
                             f"expected a header line with the columns {required}")
        return self.header, self.h, self.acc


def _read(path: Path, src: str, model: Manipulator, progress: bool, max_rows: int | None
          ) -> tuple[list[str], Header, Columns]:
    """Stream the file once: the header, then each data row checked and appended."""
    reader = _Reader(src, model, max_rows)
    bar = tqdm(desc=f"reading {path.name}", unit=" rows", disable=not progress,
               mininterval=1.0, leave=False)
    with open(path, newline="", encoding=_encoding(path)) as fh, bar:
        for lineno, rec in _records(fh, src):
            if reader.feed(lineno, rec) and reader.rows % 10000 == 0:
                bar.update(10000)
    header, h, acc = reader.parsed()
    if reader.comments:
        c = reader.comments
        shown = ", ".join(map(str, c[:10])) + (" ..." if len(c) > 10 else "")
        warnings.warn(f"{src}: {len(c)} comment line(s) starting with # skipped (lines "
                      f"{shown})", DataWarning, stacklevel=3)
    if not acc.lines:
        raise InputError(f"{src}: no data rows after the header; expected one row per "
                         "measured point")
    return header, h, acc.columns(h)


def _units(c: Columns, h: Header, model: Manipulator, deg: bool, src: str) -> None:
    """Joint columns to rad (revolute) and the model's length unit (prismatic), positions to
    the model's length unit, in place, by the rule and checks of :mod:`zrp.units`."""
    rev = ~np.asarray(model.prismatic)
    angle, scale = joint_column_units([h.units[q] for q in h.qcols], rev, deg, src=src,
                                      length_unit=model.length_unit, names=h.qcols)
    c.q[:] = joint_values_to_rad(c.q, rev, angle, src=src, names=h.qcols, lines=c.lines,
                                 bounds=angle_bounds(model.lower, model.upper)) * scale
    for k, x in enumerate("xyz"):
        c.xyz[:, k] *= length_scale(h.units[x], model.length_unit, f"{src} column {x}")


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
        _, h, c = _read(path, src, model, progress,
                        None if max_rows is None else check_int(max_rows, "max_rows", 1))
    except OSError as exc:
        raise InputError(f"{src}: cannot read ({exc.strerror or exc})") from exc
    _units(c, h, model, deg, src)
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
