"""Trajectory measurements: time-stamped tracker points while the robot moves.

:class:`Trajectory` holds S samples (time stamps of the tracker, s), the controller's commanded
joint values at those times, and the M tool points measured at each sample. Each sample is a
"pose" of the static engine (:class:`zrp.gap.Measurements`, pose id ``s<i>``), so the static
fitting (:mod:`zrp.gap.model.problem`, :mod:`zrp.gap.fit.leastsq`) and the static effects run
unchanged on the same data. The commanded joint values are interpolated by a cubic spline
(eq. M0) for the velocities, accelerations and time shifts the motion effects need.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.measurements import FRAMES, Measurements
from zrp.gap.motion.choices import RATE_RANGE_HZ, TIME_UNITS

__all__ = ["MIN_SAMPLES", "RATE_RANGE_HZ", "TIME_UNITS", "Trajectory", "check_rate",
           "joints_at"]

#: fewest samples a trajectory diagnosis accepts.
MIN_SAMPLES = 50



def check_rate(t: F64, lines: NDArray[np.int64] | None, source: str) -> None:
    """Refuse a stream whose median sample rate lies outside :data:`RATE_RANGE_HZ` (time
    stamps in ms or us read as s, or a stream that is no tracker's), naming the range."""
    if t.size < 2:
        return
    dt = float(np.median(np.diff(t)))
    rate = 1.0 / dt if dt > 0 else math.inf
    lo, hi = RATE_RANGE_HZ
    if lo <= rate <= hi:
        return
    where = f"{source} line {int(lines[0])}" if lines is not None and len(lines) else source
    hint = ("are the time stamps in ms or us? name their unit: time_unit=\"ms\" "
            "(--time-unit ms on the command line)" if rate < lo else
            "the time stamps must be in s (or name their unit with time_unit, --time-unit)")
    raise InputError(f"{where}: column t has a median sample interval of {dt:g} s "
                     f"({rate:g} Hz); a tracker stream is {lo:g} Hz to {hi:g} Hz: {hint}")


def joints_at(t: F64, tq: F64, q: F64, source: str, lines: NDArray[np.int64]) -> F64:
    """The joint values at the tracker times ``t`` from the controller's stream (``tq``, its
    own clock, s; ``q`` (K, n)): a cubic spline through the stream (eq. M0), a repeated
    ``tq`` keeping its first sample; ``tq`` going backwards is refused naming the line
    (``lines``: of each stream sample). The one aligner of a tracker with joint samples: the
    CSV's ``tq`` column and a bag's joint-state topic."""
    keep = np.r_[True, np.diff(tq) > 0]
    if np.any(np.diff(tq) < 0):
        i = int(np.argmax(np.diff(tq) < 0)) + 1
        raise InputError(f"{source} line {lines[i]}: tq goes backwards; the controller's "
                         "time stamps must be in order")
    return CubicSpline(tq[keep], q[keep], axis=0)(t)


def _frozen(a: ArrayLike) -> F64:
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Validated time-stamped measurements (S samples, n joints, M tool points).

    Attributes:
        t: tracker time stamps, s, strictly increasing, shape (S,).
        q: commanded joint values at t (controller), rad or model length unit, shape (S, n).
        xyz: measured tool points, model length unit, shape (S, M, 3).
        point_labels: the M point labels.
        frame: "instrument" (unknown rigid transform, estimated) or "base".
        lines: source line of each sample's first row (messages), shape (S,).
        source: file name or description.
    """

    t: F64
    q: F64
    xyz: F64
    point_labels: tuple[str, ...] = ("p1",)
    frame: str = "instrument"
    lines: NDArray[np.int64] | None = None
    source: str = "trajectory"

    def __post_init__(self) -> None:
        t, q, xyz = self._shaped()
        s = t.shape[0]
        lines = (np.arange(s, dtype=np.int64) + 2 if self.lines is None
                 else np.asarray(self.lines, dtype=np.int64))
        self._check_values(t, q, xyz, lines)
        if len(self.point_labels) != xyz.shape[1]:
            raise InputError(f"{self.source}: {xyz.shape[1]} points per sample but "
                             f"{len(self.point_labels)} point labels")
        if self.frame not in FRAMES:
            raise InputError(f"frame: {self.frame!r} is not a frame; expected one of {FRAMES}")
        object.__setattr__(self, "t", _frozen(t))
        object.__setattr__(self, "q", _frozen(q))
        object.__setattr__(self, "xyz", _frozen(xyz))
        object.__setattr__(self, "lines", lines)
        object.__setattr__(self, "point_labels", tuple(str(p) for p in self.point_labels))

    def _shaped(self) -> tuple[F64, F64, F64]:
        """t (S,), q (S, n) and xyz (S, M, 3) (one point: (S, 3) allowed), S >= MIN_SAMPLES."""
        t = np.asarray(self.t, dtype=float)
        q = np.asarray(self.q, dtype=float)
        xyz = np.asarray(self.xyz, dtype=float)
        if xyz.ndim == 2:
            xyz = xyz[:, None, :]
        s = t.shape[0] if t.ndim == 1 else -1
        if t.ndim != 1 or q.ndim != 2 or q.shape[0] != s or xyz.shape[:1] != (s,) \
                or xyz.ndim != 3 or xyz.shape[2] != 3:
            raise InputError(f"{self.source}: expected t (S,), q (S, n), xyz (S, M, 3); got "
                             f"{t.shape}, {q.shape}, {xyz.shape}")
        if s < MIN_SAMPLES:
            raise InputError(f"{self.source}: {s} samples; a trajectory diagnosis needs at "
                             f"least {MIN_SAMPLES}")
        return t, q, xyz

    def _check_values(self, t: F64, q: F64, xyz: F64, lines: NDArray[np.int64]) -> None:
        """Every value finite, the times strictly increasing (errors name the line)."""
        s = t.shape[0]
        for name, a in (("t", t), ("q", q), ("xyz", xyz)):
            bad = ~np.isfinite(a.reshape(s, -1)).all(axis=1)
            if bad.any():
                i = int(np.argmax(bad))
                raise InputError(f"{self.source} line {lines[i]}: {name} is not a finite number")
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.argmax(dt <= 0)) + 1
            raise InputError(f"{self.source} line {lines[i]}: t = {float(t[i])!r} s does not "
                             f"increase (previous sample t = {float(t[i - 1])!r} s); samples "
                             "must be in time order")

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])

    @property
    def n_joints(self) -> int:
        return int(self.q.shape[1])

    @property
    def duration(self) -> float:
        """s."""
        return float(self.t[-1] - self.t[0])

    @property
    def rate_hz(self) -> float:
        """Median sample rate, Hz."""
        return float(1.0 / np.median(np.diff(self.t)))

    @cached_property
    def spline(self) -> CubicSpline:
        """q(t), the commanded joints as a cubic spline (eq. M0; natural ends)."""
        return CubicSpline(self.t, self.q, axis=0, bc_type="natural")

    @cached_property
    def qd(self) -> F64:
        """Commanded joint velocities at the samples, shape (S, n)."""
        return _frozen(self.spline(self.t, 1))

    @cached_property
    def qdd(self) -> F64:
        """Commanded joint accelerations at the samples, shape (S, n)."""
        return _frozen(self.spline(self.t, 2))

    @cached_property
    def measurements(self) -> Measurements:
        """The same data as static measurements: one pose per sample (``s<i>``)."""
        s, m = self.xyz.shape[:2]
        pose = np.repeat(np.array([f"s{i}" for i in range(s)], dtype=object), m)
        point = np.tile(np.array(self.point_labels, dtype=object), s)
        return Measurements(pose, point, np.repeat(self.q, m, axis=0),
                            self.xyz.reshape(-1, 3), self.frame, np.repeat(self.t, m),
                            None, None, None, None, np.repeat(self.lines, m), self.source)

    def subset(self, samples: ArrayLike) -> Trajectory:
        """The samples at the given indices (in order)."""
        i = np.asarray(samples, dtype=np.int64)
        return Trajectory(self.t[i], self.q[i], self.xyz[i], self.point_labels, self.frame,
                          self.lines[i], self.source)
