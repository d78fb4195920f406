"""Target files of ``zrp compensate``: reading the targets, writing the commands (CSV).

Targets CSV, one row per target, in program order: ``target`` (id), ``q1``..``qn`` (the
program's joint values, rad or deg with ``deg=True``; the seed of the solve), and optionally
``x, y, z`` (desired tool-point position; without them the target is the nominal model's pose
at q: a joint program) and ``qw, qx, qy, qz`` (desired hand orientation in the base frame, a
unit quaternion, with x, y, z). A joint or position column may declare its unit
(``q1[deg]``, ``x[m]``; the rule and checks of :mod:`zrp.units`: seeds in degrees read as
radians are refused). Errors name the file, line and column.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.calibration.compensation import Compensation
from zrp.errors import InputError
from zrp.escape import csv_text, csv_uncell
from zrp.model.manipulator import Manipulator
from zrp.output import write_text
from zrp.rotations import matrix_from_er
from zrp.textio import iter_lines
from zrp.units import (
    angle_bounds,
    joint_column_units,
    joint_values_to_rad,
    length_scale,
    split_unit,
)

__all__ = ["MAX_TARGETS", "Commands", "Targets", "load_commands", "load_targets",
           "write_commands"]

#: Most rows read from a targets or commands file.
MAX_TARGETS = 1_000_000

#: The columns :func:`write_commands` writes besides target and q1..qn.
COMMAND_FLAGS = ("residual", "orientation_residual", "uncompensated", "sigma_min",
                 "near_singular", "near_limit", "converged", "outside_measured")



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


def _read_rows(path: str | Path, what: str) -> list[list[str]]:
    """The non-empty CSV records of ``path``, streamed (:func:`zrp.textio.iter_lines`: a
    regular file, lines bounded; at most :data:`MAX_TARGETS` rows); a header and a row at
    least."""
    src = str(path)
    reader = csv.reader(iter_lines(path, label=src))
    rows: list[list[str]] = []
    try:
        for r in reader:
            if len(rows) > MAX_TARGETS:
                raise InputError(f"{src}, line {reader.line_num}: more than {MAX_TARGETS:,} "
                                 "rows; split the file")
            if r:
                rows.append(r)
    except csv.Error as exc:
        raise InputError(f"{src}, line {reader.line_num}: not a CSV file ({exc})") from None
    if len(rows) < 2:
        raise InputError(f"{src}: no {what} (a header and at least one row expected)")
    return rows


def _header(rows: list[list[str]], src: str) -> tuple[list[str], dict[str, str | None]]:
    """The column names and the unit each declares (zrp.units.split_unit)."""
    parsed = [split_unit(h, f"{src}, line 1") for h in rows[0]]
    return [h for h, _ in parsed], dict(parsed)


def _positions(xyz: F64, unit: dict[str, str | None], model: Manipulator | None, src: str
               ) -> F64:
    """x, y, z in the model's length unit (a declared unit converted)."""
    if all(unit[c] is None for c in "xyz"):
        return xyz
    if model is None:
        raise InputError(f"{src}, line 1: x, y, z declare a unit; the model is needed to "
                         "convert it")
    return xyz * [length_scale(unit[c], model.length_unit, f"{src} column {c}") for c in "xyz"]


def load_targets(path: str | Path, n: int, *, deg: bool = False,
                 model: Manipulator | None = None) -> Targets:
    """Read a targets CSV for a robot with ``n`` joints (see the module doc); ``model`` (with
    n joints) tells the prismatic joints, the joint limits and the length unit (None: all
    revolute, positions in the model's unit, unit-less).

    Raises:
        InputError: unreadable file, bad header, field count, non-numbers (file, line, column).
    """
    src = str(path)
    rows = _read_rows(path, "targets")
    header, unit = _header(rows, src)
    cols, has_xyz, has_quat = _columns(header, n, src)
    ids, vals = [], []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(f"{src}, line {i}: {len(r)} fields, expected {len(header)}")
        rec = dict(zip(header, (c.strip() for c in r), strict=True))
        ids.append(csv_uncell(rec["target"]))
        vals.append([_number(rec[c], src, i, c) for c in cols[1:]])
    if len(set(ids)) != len(ids):
        raise InputError(f"{src}: repeated target ids")
    a = np.array(vals, dtype=float)
    q = _joints(a[:, :n], [unit[f"q{k}"] for k in range(1, n + 1)], deg, model, src)
    xyz = _positions(a[:, n:n + 3], unit, model, src) if has_xyz else None
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


def _joints(q: F64, declared: list[str | None], deg: bool, model: Manipulator | None,
            src: str) -> F64:
    """Program joint values to rad by the rule and checks of :mod:`zrp.units`."""
    n = q.shape[1]
    rev = np.ones(n, bool) if model is None else ~np.asarray(model.prismatic)
    names = [f"q{k}" for k in range(1, n + 1)]
    angle, scale = joint_column_units(declared, rev, deg, src=src, names=names,
                                      length_unit="mm" if model is None else model.length_unit)
    bounds = None if model is None else angle_bounds(model.lower, model.upper)
    return joint_values_to_rad(q, rev, angle, src=src, names=names,
                               lines=np.arange(2, len(q) + 2), bounds=bounds) * scale


@dataclass(frozen=True, eq=False)
class Commands:
    """A commands CSV read back (T rows): ``ids``, ``q`` (rad, (T, n)) and ``converged``
    (T,) bool."""

    ids: tuple[str, ...]
    q: F64
    converged: np.ndarray


def _check_command_columns(header: list[str], joints: list[str], src: str) -> None:
    missing = [c for c in ["target", *joints, "converged"] if c not in header]
    unknown = [c for c in header if c not in ("target", *joints, *COMMAND_FLAGS)]
    if missing or unknown:
        raise InputError(f"{src}, line 1: expected the columns of zrp compensate's output "
                         f"(target, q1..q{len(joints)}, {', '.join(COMMAND_FLAGS)}); missing "
                         f"{missing}, unknown {unknown}")


def load_commands(path: str | Path, model: Manipulator, *, deg: bool = False) -> Commands:
    """Read the commands CSV of ``zrp compensate`` (:func:`write_commands`) for ``model``;
    joint columns by the unit rule of :mod:`zrp.units` (``q1[deg]`` declared, or ``deg``).

    Raises:
        InputError: unreadable file, missing or unknown columns, non-numbers (file, line,
            column); UnitError: a unit mix-up.
    """
    src = str(path)
    rows = _read_rows(path, "commands")
    header, unit = _header(rows, src)
    n = model.n
    joints = [f"q{k}" for k in range(1, n + 1)]
    _check_command_columns(header, joints, src)
    col = {c: i for i, c in enumerate(header)}
    ids, vals, conv = [], [], []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise InputError(f"{src}, line {i}: {len(r)} fields, expected {len(header)}")
        ids.append(csv_uncell(r[col["target"]].strip()))
        vals.append([_number(r[col[c]], src, i, c) for c in joints])
        conv.append(_number(r[col["converged"]], src, i, "converged") == 1.0)
    q = _joints(np.array(vals), [unit[c] for c in joints], deg, model, src)
    return Commands(tuple(ids), q, np.array(conv))


def write_commands(comp: Compensation, path: str | Path, *, deg: bool = False,
                   overwrite: bool = False) -> Path:
    """Write the commands with the predicted residual and the flags per target (CSV).

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
    """
    n = comp.q_command.shape[1]
    q = np.degrees(comp.q_command) if deg else comp.q_command
    header = ["target", *[f"q{k}{'[deg]' if deg else ''}" for k in range(1, n + 1)],
              "residual", *COMMAND_FLAGS[1:]]
    ori = comp.orientation_residual
    rows = ([t, *(repr(float(v)) for v in q[i]), repr(float(comp.residual[i])),
             "" if ori is None else repr(float(ori[i])),
             repr(float(comp.uncompensated[i])), repr(float(comp.sigma_min[i])),
             int(comp.near_singular[i]), int(comp.near_limit[i]), int(comp.converged[i]),
             int(comp.outside_measured[i])]
            for i, t in enumerate(comp.target_ids))
    return write_text(path, csv_text(header, rows), overwrite=overwrite)
