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

The file is read line by line (large files never sit in memory as text); a malformed row, a
missing column, a non-number, a NaN or a time going backwards is an error naming the file and
line.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from zrp.errors import InputError
from zrp.gap.motion.data import Trajectory
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path
from zrp.units import angle_bounds, joint_values_to_rad

__all__ = ["load_trajectory", "write_trajectory"]


def _header(row: list[str], n: int, name: str) -> dict[str, int]:
    cols = {c.strip(): i for i, c in enumerate(row)}
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
    if not np.isfinite(x):
        raise InputError(f"{name} line {line}: column {col} is {v!r}; expected a finite number")
    return x


def load_trajectory(path: str | os.PathLike[str], model: Manipulator, *, deg: bool = False,
                    frame: str = "instrument") -> Trajectory:
    """Read a trajectory CSV (see the module doc) for ``model`` (n joints)."""
    p = Path(path)
    name = p.name
    n = model.n
    qcols = [f"q{k}" for k in range(1, n + 1)]
    try:
        fh = p.open(newline="", encoding="utf-8")
    except OSError as exc:
        raise InputError(f"data {path}: cannot read: {exc.strerror}") from exc
    with fh:
        reader = csv.reader(fh)
        try:
            cols = _header(next(reader), n, name)
        except StopIteration:
            raise InputError(f"{name}: empty file; expected a header line") from None
        numeric = ["t", *qcols, "x", "y", "z"] + (["tq"] if "tq" in cols else [])
        idx = [cols[c] for c in numeric]
        ipoint = cols.get("point")
        vals: list[list[float]] = []
        points: list[str] = []
        lines: list[int] = []
        for line, row in enumerate(reader, start=2):
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != len(cols):
                raise InputError(f"{name} line {line}: {len(row)} fields, expected {len(cols)}")
            vals.append([_num(row[i], name, line, c) for i, c in zip(idx, numeric, strict=True)])
            points.append(row[ipoint].strip() if ipoint is not None else "p1")
            lines.append(line)
    if not vals:
        raise InputError(f"{name}: no data rows")
    a = np.array(vals)
    return _assemble(a, numeric, points, np.array(lines), model, deg, frame, name)


def _assemble(a: np.ndarray, numeric: list[str], points: list[str], lines: np.ndarray,
              model: Manipulator, deg: bool, frame: str, name: str) -> Trajectory:
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
    labels = list(dict.fromkeys(points))
    m = len(labels)
    starts = np.flatnonzero(np.r_[True, np.diff(t) > 0])
    counts = np.diff(np.r_[starts, t.size])
    bad = np.flatnonzero(counts != m)
    if bad.size:
        i = int(starts[bad[0]])
        raise InputError(f"{name} line {lines[i]}: sample t = {float(t[i])!r} s has "
                         f"{counts[bad[0]]} points; every sample must measure all {m} points "
                         f"({', '.join(labels)})")
    pts = np.array(points, dtype=object).reshape(-1, m)
    order = np.argsort(np.vectorize(labels.index)(pts), axis=1)
    if not np.all(pts[np.arange(pts.shape[0])[:, None], order] == np.array(labels)):
        raise InputError(f"{name}: a sample repeats a point label; each sample measures each "
                         "point once")
    rows = starts[:, None] + order
    ts = t[starts]
    if "tq" in numeric:
        tq = a[:, -1]
        keep = np.r_[True, np.diff(tq) > 0]
        if np.any(np.diff(tq) < 0):
            i = int(np.argmax(np.diff(tq) < 0)) + 1
            raise InputError(f"{name} line {lines[i]}: tq goes backwards; the controller's "
                             "time stamps must be in order")
        qs = CubicSpline(tq[keep], q[keep], axis=0)(ts)
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
    with atomic_path(path, overwrite=overwrite) as tmp, tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t", "point", *[f"q{k}" for k in range(1, n + 1)], "x", "y", "z"])
        for i in range(traj.n_samples):
            qi = [repr(float(v)) for v in q[i]]
            for j, lab in enumerate(traj.point_labels):
                w.writerow([repr(float(traj.t[i])), lab, *qi,
                            *(repr(float(v)) for v in traj.xyz[i, j])])
    return Path(path)
