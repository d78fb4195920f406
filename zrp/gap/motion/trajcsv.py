"""The trajectory CSV: a strict, streaming reader and the writer.

One row per measured point, rows in time order::

    t,point,q1,...,qn,x,y,z[,tq]

* ``t`` (required): the tracker's time stamp, s. Rows with the same ``t`` are one sample
  (several reflectors); ``point`` is optional (one reflector, label ``p1``).
* ``q1..qn``: the controller's commanded joint values (rad; degrees for revolute joints with
  ``deg``; the model's length unit for prismatic joints).
* ``tq`` (optional): the controller's time stamp of the joint values on that row, s, when the
  controller logs them on its own clock; q at the tracker times is then interpolated from the
  (tq, q) stream by a cubic spline. Without it, q is taken at ``t``.

The file is read line by line through :func:`zrp.textio.iter_lines` (a regular file only;
a line longer than 1 Mi characters refused while it streams) into compact arrays; a malformed
row, a missing column, a non-number, a NaN or a time going backwards is an error naming the
file and line. The static loader's unit check holds here too, in its words: revolute joint
values beyond 2 pi are refused as degrees (pass ``deg``), and a median sample rate outside
5 Hz .. 100 kHz is refused (time stamps in ms or us: pass ``time_unit``).
"""

from __future__ import annotations

import csv
import math
import os
from array import array
from pathlib import Path
from typing import Any

import numpy as np

from zrp.errors import InputError
from zrp.escape import csv_text, csv_uncell
from zrp.gap.data.choices import MAX_ROWS
from zrp.gap.motion.data import TIME_UNITS, Trajectory, check_rate, joints_at
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path
from zrp.textio import iter_lines
from zrp.units import angle_bounds, joint_values_to_rad

__all__ = ["load_trajectory", "write_trajectory"]


def _header(row: list[str], n: int, name: str) -> dict[str, int]:
    cols = {c.strip(): i for i, c in enumerate(row)}
    if len(cols) != len(row):
        seen: set[str] = set()
        twice = next(c.strip() for c in row if c.strip() in seen or seen.add(c.strip()))
        raise InputError(f"{name} line 1: column {twice!r} appears twice; each column once")
    need = ["t", *[f"q{k}" for k in range(1, n + 1)], "x", "y", "z"]
    missing = [c for c in need if c not in cols]
    if missing:
        raise InputError(f"{name} line 1: missing column(s) {', '.join(missing)}; a trajectory "
                         f"CSV needs t, q1..q{n}, x, y, z (optional point, tq)")
    return cols


def _num(v: str, name: str, line: int, col: str) -> float:
    try:
        x = float(v)
    except ValueError:
        raise InputError(f"{name} line {line}: column {col} is {v!r}; expected a number") \
            from None
    if not math.isfinite(x):
        raise InputError(f"{name} line {line}: column {col} is {v!r}; expected a finite number")
    return x


def _rows(reader: Any, cols: dict[str, int], numeric: list[str], name: str,
          max_rows: int | None) -> tuple[array, list[str] | None, array]:
    """The data rows, streamed into compact arrays: values (flat, row-major), point labels
    (None without a point column) and line numbers."""
    idx = [cols[c] for c in numeric]
    pairs = list(zip(idx, numeric, strict=True))
    ipoint = cols.get("point")
    vals, lines = array("d"), array("q")
    points: list[str] | None = [] if ipoint is not None else None
    ncols = len(cols)
    line = reader.line_num + 1
    for row in reader:
        if row and any(c.strip() for c in row):
            if len(row) != ncols:
                raise InputError(f"{name} line {line}: {len(row)} fields, expected {ncols}")
            if max_rows is not None and len(lines) >= max_rows:
                raise InputError(
                    f"{name} line {line}: more than max_rows={max_rows} data rows; split the "
                    "file or thin it (every k-th sample), or pass a larger max_rows")
            try:
                vals.extend([float(row[i]) for i in idx])
            except ValueError:
                for i, c in pairs:
                    _num(row[i], name, line, c)
            if points is not None:
                points.append(csv_uncell(row[ipoint].strip()))  # type: ignore[index]
            lines.append(line)
        line = reader.line_num + 1
    return vals, points, lines


def load_trajectory(path: str | os.PathLike[str], model: Manipulator, *, deg: bool = False,
                    frame: str = "instrument", time_unit: str = "s",
                    max_rows: int | None = MAX_ROWS) -> Trajectory:
    """Read a trajectory CSV (see the module doc) for ``model`` (n joints).

    Args:
        deg: revolute joint values in degrees (else values beyond 2 pi are refused: they look
            like degrees; the static loader's check and wording).
        time_unit: unit of the ``t`` and ``tq`` columns, one of :data:`TIME_UNITS` (a median
            sample rate outside :data:`RATE_RANGE_HZ` is refused, naming the range).
        max_rows: most data rows read (None: no limit), refused at the first row beyond.

    The file is read through :func:`zrp.textio.iter_lines` (a regular file; lines bounded)
    into compact arrays (8 bytes a number).

    Raises:
        InputError: naming the file, line and column of the first problem.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a CSV file name, got {type(path).__name__}")
    if time_unit not in TIME_UNITS:
        raise InputError(f"time_unit: {time_unit!r} is not a time unit; expected one of "
                         f"{sorted(TIME_UNITS)}")
    p = Path(path)
    name = p.name
    n = model.n
    reader = csv.reader(iter_lines(p, label=name))
    try:
        try:
            cols = _header(next(reader), n, name)
        except StopIteration:
            raise InputError(f"{name}: empty file; expected a header line") from None
        numeric = ["t", *[f"q{k}" for k in range(1, n + 1)], "x", "y", "z"] + \
            (["tq"] if "tq" in cols else [])
        vals, points, lines = _rows(reader, cols, numeric, name, max_rows)
    except csv.Error as exc:
        raise InputError(f"{name} line {reader.line_num}: {exc}; expected a trajectory CSV"
                         ) from None
    if not lines:
        raise InputError(f"{name}: no data rows")
    a = np.frombuffer(vals, dtype=float).reshape(-1, len(numeric)).copy()
    line_no = np.frombuffer(lines, dtype=np.int64).copy()
    bad = ~np.isfinite(a)
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad)[0])
        raise InputError(f"{name} line {line_no[i]}: column {numeric[j]} is {float(a[i, j])!r}; "
                         "expected a finite number")
    a[:, 0] *= TIME_UNITS[time_unit]
    if "tq" in numeric:
        a[:, -1] *= TIME_UNITS[time_unit]
    check_rate(np.unique(a[:, 0]), line_no, name)
    return _assemble(a, numeric, points, line_no, model, deg, frame, name)


def _assemble(a: np.ndarray, numeric: list[str], points: list[str] | None,
              lines: np.ndarray, model: Manipulator, deg: bool, frame: str, name: str
              ) -> Trajectory:
    """Rows grouped into samples (equal t), point labels checked, q at the tracker times."""
    n = model.n
    t = a[:, 0]
    q = joint_values_to_rad(a[:, 1:1 + n], ~np.asarray(model.prismatic),
                            "deg" if deg else "rad", src=name, lines=lines,
                            bounds=angle_bounds(model.lower, model.upper), header=False)
    xyz = a[:, 1 + n:4 + n]
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"{name} line {lines[i]}: t = {float(t[i])!r} s is earlier than the "
                         f"previous row's {float(t[i - 1])!r} s; rows must be in time order")
    labels = ["p1"] if points is None else list(dict.fromkeys(points))
    m = len(labels)
    starts = np.flatnonzero(np.r_[True, np.diff(t) > 0])
    counts = np.diff(np.r_[starts, t.size])
    bad = np.flatnonzero(counts != m)
    if bad.size:
        i = int(starts[bad[0]])
        raise InputError(f"{name} line {lines[i]}: sample t = {float(t[i])!r} s has "
                         f"{counts[bad[0]]} points; every sample must measure all {m} points "
                         f"({', '.join(labels)})")
    if points is None:
        rows = starts[:, None]
    else:
        lut = {lab: i for i, lab in enumerate(labels)}
        code = np.fromiter((lut[x] for x in points), dtype=np.int64,
                           count=len(points)).reshape(-1, m)
        order = np.argsort(code, axis=1, kind="stable")
        if not np.all(np.take_along_axis(code, order, axis=1) == np.arange(m)):
            raise InputError(f"{name}: a sample repeats a point label; each sample measures "
                             "each point once")
        rows = starts[:, None] + order
    ts = t[starts]
    if "tq" in numeric:
        qs = joints_at(ts, a[:, -1], q, name, lines)
    else:
        qs = q[starts]
    return Trajectory(ts, qs, xyz[rows], tuple(labels), frame, lines[starts], name)


def write_trajectory(traj: Trajectory, path: str | os.PathLike[str], *, deg: bool = False,
                     model: Manipulator | None = None, overwrite: bool = False) -> Path:
    """Write ``traj`` as a trajectory CSV (q of revolute joints in degrees with ``deg``, which
    needs ``model``), atomically; an existing file is replaced only with ``overwrite``."""
    q = np.array(traj.q)
    if deg:
        if model is None:
            raise InputError("model: needed with deg=True (which joints are revolute)")
        rev = ~np.asarray(model.prismatic)
        q[:, rev] = np.degrees(q[:, rev])
    n = traj.n_joints
    rows = ([repr(float(traj.t[i])), lab, *(repr(float(v)) for v in q[i]),
             *(repr(float(v)) for v in traj.xyz[i, j])]
            for i in range(traj.n_samples) for j, lab in enumerate(traj.point_labels))
    text = csv_text(["t", "point", *[f"q{k}" for k in range(1, n + 1)], "x", "y", "z"], rows)
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="")
    return Path(path)
