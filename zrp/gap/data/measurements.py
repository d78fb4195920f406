"""Measurement data of the sim-to-real gap diagnosis: validated, immutable arrays.

:class:`Measurements` holds one row per measured point, rows in measurement order (the CSV
format and its strict reader are in :mod:`zrp.gap.data.csvfile`; :meth:`Measurements.to_csv` writes
it). Nothing is dropped silently: a wrong shape, a NaN, a repeated (pose, point) or rows of one
pose with different joint values are errors naming the source and line.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError, ZRPWarning
from zrp.escape import csv_text
from zrp.model.manipulator import MAX_LENGTH
from zrp.output import write_text

__all__ = [
    "FRAMES",
    "DataWarning",
    "Measurements",
]

FRAMES = ("instrument", "base")
OPTIONAL_SCALARS = ("t", "temp", "load")
QUAT_COLUMNS = ("qw", "qx", "qy", "qz")


class DataWarning(ZRPWarning):
    """Measurement data are usable but suspicious (repeats, unused columns, few poses)."""


def _freeze(a: NDArray) -> NDArray:
    a = np.array(a)
    a.setflags(write=False)
    return a


def _opt(a: ArrayLike | None, shape: tuple[int, ...], name: str) -> F64 | None:
    if a is None:
        return None
    try:
        arr = np.array(a, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected numbers ({exc})") from None
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        r = int(np.argwhere(bad)[0][0])
        raise InputError(f"{name}: row {r} is not a finite number ({arr.reshape(len(arr), -1)[r]})")
    return _freeze(arr)


@dataclass(frozen=True, eq=False)
class Measurements:
    """Validated measurements, one row per measured point (R rows, n joints).

    Attributes:
        pose: pose ids, shape (R,) (strings).
        point: point labels, shape (R,) (strings).
        q: joint values, rad (revolute) or length unit (prismatic), shape (R, n).
        xyz: measured positions, length unit of the model, shape (R, 3).
        frame: "instrument" (an unknown rigid transform from the base, estimated) or "base".
        t: time, s, shape (R,), or None.
        temp: temperature, deg C, shape (R,), or None.
        load: payload, kg, shape (R,), or None.
        quat: measured orientation (qw, qx, qy, qz), shape (R, 4), or None (used by
            :mod:`zrp.gap.fit.fullpose`; the stepwise search uses positions only, the final
            model is refitted with them, :mod:`zrp.gap.search.posefit`).
        direction: approach direction per joint (-1, 0, +1), shape (R, n), or None.
        lines: source line number of each row (for messages), shape (R,).
        source: file name or a description, for messages.
    """

    pose: NDArray
    point: NDArray
    q: F64
    xyz: F64
    frame: str = "instrument"
    t: F64 | None = None
    temp: F64 | None = None
    load: F64 | None = None
    quat: F64 | None = None
    direction: F64 | None = None
    lines: NDArray[np.int64] | None = None
    source: str = "measurements"

    def __post_init__(self) -> None:
        q = self._checked_q()
        r, n = q.shape
        lines = self._set_labels(r)
        if self.frame not in FRAMES:
            raise InputError(f"frame: {self.frame!r} is not a frame; expected one of {FRAMES}")
        for name, arr, shape in (("q", q, (r, n)), ("xyz", self.xyz, (r, 3))):
            object.__setattr__(self, name, _freeze(self._bounded(name, arr, shape, lines)))
        for name in OPTIONAL_SCALARS:
            object.__setattr__(self, name, _opt(getattr(self, name), (r,), name))
        object.__setattr__(self, "quat", _opt(self.quat, (r, 4), "quat"))
        object.__setattr__(self, "direction", _opt(self.direction, (r, n), "direction"))
        if self.direction is not None and not np.all(np.isin(self.direction, (-1.0, 0.0, 1.0))):
            i = int(np.argwhere(~np.isin(self.direction, (-1.0, 0.0, 1.0)))[0][0])
            raise InputError(f"{self.source} line {lines[i]}: dir columns must be -1, 0 or +1")
        self._check_structure()

    # ---- construction -------------------------------------------------------------------
    def _checked_q(self) -> F64:
        """q as numbers of shape (R, n), R >= 1 (xyz must be numbers too)."""
        try:
            q = np.array(self.q, dtype=float)
            np.array(self.xyz, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{self.source}: q and xyz: expected numbers ({exc})") from None
        if q.ndim != 2 or q.shape[0] == 0:
            raise InputError(f"{self.source}: q: expected shape (R, n) with R >= 1 rows, got "
                             f"{q.shape}")
        return q

    def _set_labels(self, r: int) -> NDArray[np.int64]:
        """Freeze the pose ids, point labels and source lines of the ``r`` rows (point "p" and
        lines 2.. when not given); returns the lines."""
        pose = np.array([str(p) for p in np.asarray(self.pose).ravel()], dtype=object)
        point = (np.array(["p"] * r, dtype=object) if self.point is None else
                 np.array([str(p) for p in np.asarray(self.point).ravel()], dtype=object))
        if pose.shape != (r,) or point.shape != (r,):
            raise InputError(f"{self.source}: pose and point: expected {r} entries each, got "
                             f"{pose.shape[0]} and {point.shape[0]}")
        lines = (np.arange(r, dtype=np.int64) + 2 if self.lines is None
                 else np.asarray(self.lines, dtype=np.int64))
        if lines.shape != (r,):
            raise InputError(f"{self.source}: lines: expected shape ({r},), got {lines.shape}")
        object.__setattr__(self, "lines", _freeze(lines))
        object.__setattr__(self, "pose", _freeze(pose))
        object.__setattr__(self, "point", _freeze(point))
        return lines

    def _bounded(self, name: str, arr: ArrayLike, shape: tuple[int, int],
                 lines: NDArray[np.int64]) -> F64:
        """``q`` or ``xyz`` of the given shape, every value finite and at most MAX_LENGTH in
        magnitude (the error names the first bad line and column)."""
        a = np.array(arr, dtype=float)
        if a.shape != shape:
            raise InputError(f"{self.source}: {name}: expected shape {shape}, got {a.shape}")
        bad = ~(np.abs(a) <= MAX_LENGTH)  # NaN fails the comparison too
        if bad.any():
            i, c = (int(v) for v in np.argwhere(bad)[0])
            col = f"q{c + 1}" if name == "q" else "xyz"[c]
            raise InputError(f"{self.source} line {lines[i]}: column {col} is {a[i, c]}; "
                             f"expected a finite number of magnitude up to {MAX_LENGTH:g}")
        return a

    # ---- structure ----------------------------------------------------------------------
    def _check_structure(self) -> None:
        seen: dict[tuple[str, str], int] = {}
        first_row: dict[str, int] = {}
        for i, (p, m) in enumerate(zip(self.pose, self.point, strict=False)):
            key = (p, m)
            if key in seen:
                raise InputError(
                    f"{self.source} line {self.lines[i]}: pose {p!r} point {m!r} was already "
                    f"measured on line {self.lines[seen[key]]}; each (pose, point) must appear "
                    "once (give repeated measurements their own pose id)")
            seen[key] = i
            if p in first_row:
                j = first_row[p]
                if not np.array_equal(self.q[i], self.q[j]):
                    c = int(np.argmax(self.q[i] != self.q[j]))
                    raise InputError(
                        f"{self.source} line {self.lines[i]}: pose {p!r} has q{c + 1} = "
                        f"{self.q[i, c]!r} but {self.q[j, c]!r} on line {self.lines[j]}; all "
                        "rows of a pose must share the same joint values")
                for name in ("temp", "load"):
                    arr = getattr(self, name)
                    if arr is not None and arr[i] != arr[j]:
                        raise InputError(
                            f"{self.source} line {self.lines[i]}: pose {p!r} has {name} "
                            f"{arr[i]} but {arr[j]} on line {self.lines[j]}; all rows of a pose "
                            f"must share {name}")
            else:
                first_row[p] = i

    @property
    def n_rows(self) -> int:
        """R, the number of measured points."""
        return int(self.q.shape[0])

    @property
    def n_joints(self) -> int:
        return int(self.q.shape[1])

    @cached_property
    def pose_ids(self) -> tuple[str, ...]:
        """Pose ids in order of first appearance (measurement order), length P."""
        return tuple(dict.fromkeys(self.pose.tolist()))

    @cached_property
    def point_labels(self) -> tuple[str, ...]:
        """Point labels in order of first appearance, length M."""
        return tuple(dict.fromkeys(self.point.tolist()))

    @cached_property
    def pose_index(self) -> NDArray[np.int64]:
        """Row -> index into :attr:`pose_ids`, shape (R,)."""
        lut = {p: i for i, p in enumerate(self.pose_ids)}
        return _freeze(np.array([lut[p] for p in self.pose], dtype=np.int64))

    @cached_property
    def point_index(self) -> NDArray[np.int64]:
        """Row -> index into :attr:`point_labels`, shape (R,)."""
        lut = {p: i for i, p in enumerate(self.point_labels)}
        return _freeze(np.array([lut[p] for p in self.point], dtype=np.int64))

    @cached_property
    def first_row(self) -> NDArray[np.int64]:
        """Index of the first row of each pose, shape (P,)."""
        _, idx = np.unique(self.pose_index, return_index=True)
        return _freeze(idx)

    @cached_property
    def q_pose(self) -> F64:
        """Joint values per pose, shape (P, n)."""
        return _freeze(self.q[self.first_row])

    def per_pose(self, name: str) -> F64 | None:
        """A per-row column (``t``, ``temp``, ``load``) reduced to one value per pose, shape (P,)
        (the pose's first row; ``t`` may differ between a pose's rows)."""
        arr = getattr(self, name)
        return None if arr is None else _freeze(arr[self.first_row])

    def approach_direction(self) -> F64:
        """Direction from which each joint approached each pose, shape (P, n), values -1/0/+1.

        From the ``dir`` columns when given; otherwise from the measurement order: the sign of
        q(pose) - q(previous pose); when a joint did not move the previous direction is kept;
        the first pose (and a joint that has not moved yet) gets 0 (unknown).
        """
        if self.direction is not None:
            return _freeze(self.direction[self.first_row])
        q = self.q_pose
        d = np.zeros_like(q)
        for i in range(1, q.shape[0]):
            step = np.sign(q[i] - q[i - 1])
            d[i] = np.where(step != 0.0, step, d[i - 1])
        return _freeze(d)

    def repeat_groups(self) -> NDArray[np.int64]:
        """Group index per pose, shape (P,): poses with identical joint values (repeats) share
        a group. Used to keep repeats on the same side of the split and for the noise floor."""
        _, inv = np.unique(self.q_pose, axis=0, return_inverse=True)
        return _freeze(np.asarray(inv, dtype=np.int64).ravel())

    def subset(self, pose_mask: ArrayLike) -> Measurements:
        """The rows of the poses selected by ``pose_mask`` (shape (P,) bool)."""
        pm = np.asarray(pose_mask, dtype=bool)
        rows = pm[self.pose_index]
        pick = (lambda a: None if a is None else a[rows])  # noqa: E731
        return Measurements(self.pose[rows], self.point[rows], self.q[rows], self.xyz[rows],
                            self.frame, pick(self.t), pick(self.temp), pick(self.load),
                            pick(self.quat), pick(self.direction), self.lines[rows],
                            self.source)

    @classmethod
    def from_arrays(cls, pose: ArrayLike, q: ArrayLike, xyz: ArrayLike, *,
                    point: ArrayLike | None = None, frame: str = "instrument",
                    t: ArrayLike | None = None, temp: ArrayLike | None = None,
                    load: ArrayLike | None = None, direction: ArrayLike | None = None,
                    source: str = "measurements", quat: ArrayLike | None = None
                    ) -> Measurements:
        """Build from arrays (q in rad, xyz in the model's length unit, quat scalar first);
        see the class doc."""
        return cls(np.asarray(pose), None if point is None else np.asarray(point),
                   q, xyz, frame,  # type: ignore[arg-type]  (converted, checked on init)
                   t, temp, load, quat, direction,  # type: ignore[arg-type]
                   None, source)

    def to_csv(self, path: str | os.PathLike[str], *, deg: bool = False,
               overwrite: bool = False) -> Path:
        """Write in the CSV format :func:`~zrp.gap.load_measurements` reads (q in deg with
        ``deg``, declared in the header, ``q1[deg]``: read back with or without deg=True),
        atomically; an existing file is replaced only with ``overwrite``.

        Raises:
            OutputExistsError: ``path`` exists and ``overwrite`` is False.
        """
        n = self.n_joints
        q = np.degrees(self.q) if deg else self.q
        unit = "[deg]" if deg else ""
        cols = ["pose", "point", *[f"q{k}{unit}" for k in range(1, n + 1)], "x", "y", "z"]
        extra = [c for c in OPTIONAL_SCALARS if getattr(self, c) is not None]
        quat = ["qw", "qx", "qy", "qz"] if self.quat is not None else []
        rows = ([self.pose[i], self.point[i], *(repr(float(v)) for v in q[i]),
                 *(repr(float(v)) for v in self.xyz[i]),
                 *(repr(float(getattr(self, c)[i])) for c in extra),
                 *([] if self.quat is None else (repr(float(v)) for v in self.quat[i]))]
                for i in range(self.n_rows))
        return write_text(path, csv_text(cols + extra + quat, rows), overwrite=overwrite)
