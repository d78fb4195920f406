"""Target files of ``zrp compensate``: reading the targets, writing the commands (CSV).

Targets CSV, one row per target, in program order: ``target`` (id), ``q1``..``qn`` (the
program's joint values, rad or deg with ``deg=True``; the seed of the solve), and optionally
``x, y, z`` (desired tool-point position; without them the target is the nominal model's pose
at q: a joint program) and ``qw, qx, qy, qz`` (desired hand orientation in the base frame, a
unit quaternion, with x, y, z). Errors name the file, line and column.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.calibration.compensation import Compensation
from zrp.errors import InputError
from zrp.output import write_text
from zrp.rotations import matrix_from_er
from zrp.textio import iter_lines

__all__ = ["MAX_TARGETS", "Targets", "load_targets", "write_commands"]

#: Most targets read from one file.
MAX_TARGETS = 1_000_000



@dataclass(frozen=True, eq=False)
class Targets:
    """Targets read from a CSV (T rows, n joints).

    Attributes:
        ids: target ids (T,).
        q: program joint values, rad, shape (T, n).
        xyz: desired positions (T, 3) or None (a joint program).
        rotation: desired hand frames (T, 3, 3) or None.
    """

    ids: tuple[str, ...]
    q: F64
    xyz: F64 | None
    rotation: F64 | None


def _number(text: str, src: str, line: int, col: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{src}, line {line}, column {col}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{src}, line {line}, column {col}: {text!r} is not finite")
    return v


def _columns(header: list[str], n: int, src: str) -> tuple[list[str], bool, bool]:
    joints = [f"q{k}" for k in range(1, n + 1)]
    has_xyz = all(c in header for c in "xyz")
    has_quat = all(c in header for c in ("qw", "qx", "qy", "qz"))
    cols = ["target", *joints, *("xyz" if has_xyz else ()),
            *(("qw", "qx", "qy", "qz") if has_quat else ())]
    if has_quat and not has_xyz:
        raise InputError(f"{src}, line 1: qw..qz need x, y, z")
    if sorted(header) != sorted(cols):
        missing = [c for c in cols if c not in header]
        extra = [c for c in header if c not in cols]
        raise InputError(f"{src}, line 1: expected columns {cols} (x, y, z and qw..qz "
                         f"optional); missing {missing}, unknown {extra}")
    return cols, has_xyz, has_quat


def _read_rows(path: str | Path, src: str) -> list[list[str]]:
    """The non-empty records of the file (:func:`zrp.textio.iter_lines`: a regular file,
    lines bounded), at most :data:`MAX_TARGETS` + 1."""
    reader = csv.reader(iter_lines(path, label=src))
    rows = []
    try:
        for r in reader:
            if len(rows) > MAX_TARGETS:
                raise InputError(f"{src}, line {reader.line_num}: more than {MAX_TARGETS:,} "
                                 "targets; split the program")
            if r:
                rows.append(r)
    except csv.Error as exc:
        raise InputError(f"{src}, line {reader.line_num}: not a CSV file ({exc})") from None
    return rows


def load_targets(path: str | Path, n: int, *, deg: bool = False) -> Targets:
    """Read a targets CSV for a robot with ``n`` joints (see the module doc).

    Raises:
        InputError: unreadable file, bad header, field count, non-numbers (file, line, column).
    """
    src = str(path)
    rows = _read_rows(path, src)
    if len(rows) < 2:
        raise InputError(f"{src}: no targets (a header and at least one row expected)")
    header = [h.strip() for h in rows[0]]
    cols, has_xyz, has_quat = _columns(header, n, src)
    ids, vals = [], []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(f"{src}, line {i}: {len(r)} fields, expected {len(header)}")
        rec = dict(zip(header, (c.strip() for c in r), strict=True))
        ids.append(rec["target"])
        vals.append([_number(rec[c], src, i, c) for c in cols[1:]])
    if len(set(ids)) != len(ids):
        raise InputError(f"{src}: repeated target ids")
    a = np.array(vals, dtype=float)
    q = np.radians(a[:, :n]) if deg else a[:, :n]
    xyz = a[:, n:n + 3] if has_xyz else None
    rot = None
    if has_quat:
        quat = a[:, n + 3:n + 7]
        norm = np.linalg.norm(quat, axis=1)
        bad = np.flatnonzero(np.abs(norm - 1.0) > 1e-6)
        if bad.size:
            raise InputError(f"{src}, line {bad[0] + 2}: qw..qz is not a unit quaternion "
                             f"(norm {norm[bad[0]]:.6g})")
        rot = matrix_from_er(quat / norm[:, None])
    return Targets(tuple(ids), q, xyz, rot)


def write_commands(comp: Compensation, path: str | Path, *, deg: bool = False,
                   overwrite: bool = False) -> Path:
    """Write the commands with the predicted residual and the flags per target (CSV).

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
    """
    n = comp.q_command.shape[1]
    q = np.degrees(comp.q_command) if deg else comp.q_command
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["target", *[f"q{k}" for k in range(1, n + 1)], "residual",
                "orientation_residual", "uncompensated", "sigma_min", "near_singular",
                "near_limit", "converged"])
    ori = comp.orientation_residual
    for i, t in enumerate(comp.target_ids):
        w.writerow([t, *(repr(float(v)) for v in q[i]), repr(float(comp.residual[i])),
                    "" if ori is None else repr(float(ori[i])),
                    repr(float(comp.uncompensated[i])), repr(float(comp.sigma_min[i])),
                    int(comp.near_singular[i]), int(comp.near_limit[i]),
                    int(comp.converged[i])])
    return write_text(path, buf.getvalue(), overwrite=overwrite)
