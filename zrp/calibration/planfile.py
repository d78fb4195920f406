"""The plan file of ``zrp plan``, read back by ``zrp measure --poses plan.csv``.

One row per pose, in measurement order: ``pose`` (id), ``q1``..``qn`` (rad, or the unit the
header declares, ``q1[deg]``: the rule and checks of :mod:`zrp.units`; prismatic joints in the
model's length unit) and ``dir1``..``dirn`` (the planned approach direction of each joint,
-1/+1; 0 leaves it to the measuring procedure). Errors name the file, line and column.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.calibration.planning import Plan
from zrp.errors import InputError
from zrp.escape import csv_text
from zrp.model.manipulator import Manipulator
from zrp.output import write_text
from zrp.textio import read_text
from zrp.units import angle_bounds, joint_column_units, joint_values_to_rad, split_unit

__all__ = ["PlannedPoses", "read_plan", "write_plan"]


@dataclass(frozen=True, eq=False)
class PlannedPoses:
    """The poses of a plan file (P poses, n joints).

    Attributes:
        ids: pose ids (P,); q: joint values, rad (length unit for prismatic joints), (P, n);
        direction: planned approach direction per pose and joint, -1/0/+1, (P, n).
    """

    ids: tuple[str, ...]
    q: F64
    direction: F64


def write_plan(plan: Plan, model: Manipulator, path: str | Path, *, deg: bool = False,
               overwrite: bool = False) -> Path:
    """Write ``plan`` as a plan file (revolute q in degrees with ``deg``, declared
    ``q1[deg]``), atomically; an existing file is replaced only with ``overwrite``."""
    n = model.n
    rev = ~np.asarray(model.prismatic)
    q = np.where(rev, np.degrees(plan.q), plan.q) if deg else plan.q
    header = ["pose", *[f"q{k}[deg]" if deg and rev[k - 1] else f"q{k}"
                        for k in range(1, n + 1)], *[f"dir{k}" for k in range(1, n + 1)]]
    rows = ([f"P{i + 1:03d}", *(repr(float(v)) for v in q[i]),
             *(int(v) for v in plan.direction[i])] for i in range(len(q)))
    return write_text(path, csv_text(header, rows), overwrite=overwrite)


def _number(text: str, src: str, line: int, col: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{src} line {line}: column {col} is {text!r}; expected a number"
                         ) from None
    if not math.isfinite(v):
        raise InputError(f"{src} line {line}: column {col} is {text!r}; expected a finite "
                         "number")
    return v


def _rows(path: Path, src: str) -> list[list[str]]:
    try:
        text = read_text(path, label=src)  # a regular file, size checked, BOM dropped
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{src}: cannot read the plan file: {exc}") from None
    try:
        return [r for r in csv.reader(io.StringIO(text)) if r]
    except csv.Error as exc:
        raise InputError(f"{src}: not a CSV plan file ({exc})") from None


def _columns(header: list[str], expected: list[str], model: Manipulator, src: str
             ) -> dict[str, int]:
    """Column positions; exactly the ``expected`` columns, in any order."""
    if sorted(header) != sorted(expected):
        missing = [c for c in expected if c not in header]
        extra = [c for c in header if c not in expected]
        raise InputError(f"{src} line 1: expected the columns pose, q1..q{model.n}, "
                         f"dir1..dir{model.n} of {model.name!r}; missing {missing}, unknown "
                         f"{extra}")
    return {c: i for i, c in enumerate(header)}


def read_plan(path: str | Path, model: Manipulator, *, deg: bool = False) -> PlannedPoses:
    """Read a plan file for ``model`` (module doc); joint columns without a unit are rad, or
    degrees with ``deg``.

    Raises:
        InputError: missing or unknown columns, non-numbers, directions other than -1/0/+1,
            a repeated pose id (file, line, column); UnitError: a unit mix-up (zrp.units).
    """
    src = str(path)
    rows = _rows(Path(path), src)
    if len(rows) < 2:
        raise InputError(f"{src}: no poses (a header and at least one row expected)")
    parsed = [split_unit(h, f"{src} line 1") for h in rows[0]]
    unit = dict(parsed)
    n = model.n
    qcols = [f"q{k}" for k in range(1, n + 1)]
    dcols = [f"dir{k}" for k in range(1, n + 1)]
    col = _columns([h for h, _ in parsed], ["pose", *qcols, *dcols], model, src)
    ids, q, d = [], [], []
    for line, r in enumerate(rows[1:], start=2):
        if len(r) != len(col):
            raise InputError(f"{src} line {line}: {len(r)} fields, expected {len(col)}")
        ids.append(r[col["pose"]].strip())
        q.append([_number(r[col[c]], src, line, c) for c in qcols])
        d.append([_number(r[col[c]], src, line, c) for c in dcols])
        if any(v not in (-1.0, 0.0, 1.0) for v in d[-1]):
            raise InputError(f"{src} line {line}: dir1..dir{n} must be -1, 0 or +1")
    if len(set(ids)) != len(ids) or "" in ids:
        raise InputError(f"{src}: pose ids must be unique and not empty")
    rev = ~np.asarray(model.prismatic)
    angle, scale = joint_column_units([unit[c] for c in qcols], rev, deg, src=src,
                                      length_unit=model.length_unit, names=qcols)
    qa = joint_values_to_rad(np.array(q), rev, angle, src=src, names=qcols,
                             lines=np.arange(2, len(q) + 2),
                             bounds=angle_bounds(model.lower, model.upper)) * scale
    return PlannedPoses(tuple(ids), qa, np.array(d))
