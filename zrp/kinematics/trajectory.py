"""Desired end-effector trajectories: time functions of p (position, velocity, acceleration)
and, optionally, of the hand orientation.

Every trajectory has a ``duration`` (s) and ``evaluate(t)`` for times of shape (m,) in
[0, duration], returning a :class:`TrajectorySample`. Positions are in the model's length unit.
The hand orientation is held at its start value unless an ``orientation`` law is given: a
callable ``t (m,) -> (er (m, 4), omega (m, 3))`` returning the Euler-Rodrigues parameters of
the hand rotation R_n and its angular velocity (rad/s, base frame).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.choices import TIME_LAWS

__all__ = [
    "TIME_LAWS",
    "Circle",
    "FunctionTrajectory",
    "Line",
    "OrientationLaw",
    "TimeLaw",
    "Trajectory",
    "TrajectorySample",
]

OrientationLaw = Callable[[F64], tuple[F64, F64]]


def _vec3(value: ArrayLike, name: str) -> F64:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected 3 numbers, got {value!r}") from exc
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected 3 finite numbers, got {value!r}")
    return arr


def _positive(value: float, name: str, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number in {unit}, got {value!r}") from exc
    if not np.isfinite(v) or v <= 0.0:
        raise InputError(f"{name}: expected a positive finite number in {unit}, got {value!r}")
    return v


@dataclass(frozen=True)
class TimeLaw:
    """A normalised motion law s(tau), tau in [0, 1], s(0) = 0, s(1) = 1, at rest at both ends.

    * ``quintic``: s = 10 tau^3 - 15 tau^4 + 6 tau^5 (zero velocity and acceleration at ends).
    * ``cycloidal``: s = tau - sin(2 pi tau) / (2 pi) (likewise, with bounded jerk).
    """

    kind: Literal["quintic", "cycloidal"] = "quintic"

    def __post_init__(self) -> None:
        if self.kind not in TIME_LAWS:
            raise InputError(f"time_law: {self.kind!r} is unknown; expected one of {TIME_LAWS}")

    def __call__(self, tau: ArrayLike) -> tuple[F64, F64, F64]:
        """s, ds/dtau, d2s/dtau2 for tau of shape (m,)."""
        t = np.asarray(tau, dtype=float)
        if self.kind == "quintic":
            s = t**3 * (10.0 + t * (-15.0 + 6.0 * t))
            ds = 30.0 * t**2 * (1.0 - t) ** 2
            dds = 60.0 * t * (1.0 - t) * (1.0 - 2.0 * t)
        else:
            w = 2.0 * np.pi
            s = t - np.sin(w * t) / w
            ds = 1.0 - np.cos(w * t)
            dds = w * np.sin(w * t)
        return s, ds, dds


@dataclass(frozen=True, eq=False)
class TrajectorySample:
    """Desired values at times ``t`` (shape (m,)): position, velocity, acceleration (m, 3),
    and, when the trajectory has an orientation law, ``er`` (m, 4) and ``omega`` (m, 3)."""

    t: F64
    position: F64
    velocity: F64
    acceleration: F64
    er: F64 | None = None
    omega: F64 | None = None


class Trajectory(ABC):
    """Base class: subclasses define ``duration`` and ``_evaluate``."""

    duration: float
    orientation: OrientationLaw | None

    def check_times(self, t: ArrayLike) -> F64:
        arr = np.atleast_1d(np.asarray(t, dtype=float))
        if arr.ndim != 1 or not np.all(np.isfinite(arr)):
            raise InputError("t: expected a 1-D array of finite times in s")
        tol = 1e-12 * self.duration
        if arr.size and (arr.min() < -tol or arr.max() > self.duration + tol):
            raise InputError(f"t: times must lie in [0, {self.duration:g}] s (the trajectory's "
                             f"duration); got [{arr.min():g}, {arr.max():g}]")
        return np.clip(arr, 0.0, self.duration)  # only rounding-level excursions reach here

    def evaluate(self, t: ArrayLike) -> TrajectorySample:
        """Desired position, velocity and acceleration (and orientation) at times ``t`` (s)."""
        tt = self.check_times(t)
        p, v, a = self._evaluate(tt)
        er = om = None
        if self.orientation is not None:
            er, om = self.orientation(tt)
            er = np.asarray(er, dtype=float).reshape(tt.size, 4)
            om = np.asarray(om, dtype=float).reshape(tt.size, 3)
            if not (np.all(np.isfinite(er)) and np.all(np.isfinite(om))):
                raise InputError("orientation: the orientation law returned non-finite values")
        return TrajectorySample(tt, p, v, a, er, om)

    @abstractmethod
    def _evaluate(self, t: F64) -> tuple[F64, F64, F64]: ...

    @property
    def start(self) -> F64:
        """Desired position at t = 0, shape (3,)."""
        return self._evaluate(np.zeros(1))[0][0]


@dataclass(frozen=True, eq=False)
class Circle(Trajectory):
    """A circle traversed once (or ``turns`` times) with a time law at rest at both ends.

    Attributes:
        center: shape (3,), length unit.
        normal: plane normal, shape (3,) (normalised; the sense of travel is right-handed
            about it).
        start: start point on the circle, shape (3,); the radius is |start - center|.
        duration: s.
        radius: optional check: if given it must equal |start - center| (rel. 1e-9).
        time_law: "quintic" or "cycloidal".
        turns: number of revolutions (default 1).
        orientation: optional orientation law (default: held at its start value).
    """

    center: F64
    normal: F64
    start_point: F64
    duration: float = 4.0
    radius: float | None = None
    time_law: str = "quintic"
    turns: float = 1.0
    orientation: OrientationLaw | None = field(default=None)

    def __post_init__(self) -> None:
        c = _vec3(self.center, "center")
        n = _vec3(self.normal, "normal")
        s = _vec3(self.start_point, "start")
        nn = np.linalg.norm(n)
        if nn < 1e-12:
            raise InputError("normal: is a zero vector; expected the circle plane's normal")
        n = n / nn
        d = s - c
        r = float(np.linalg.norm(d))
        if r <= 0.0:
            raise InputError("start: coincides with center; the radius must be positive")
        if abs(d @ n) > 1e-9 * r:
            raise InputError(f"start: is {d @ n:.6g} out of the circle's plane (start - center "
                             f"must be perpendicular to normal)")
        if self.radius is not None:
            rr = _positive(self.radius, "radius", "length units")
            if abs(rr - r) > 1e-9 * rr:
                raise InputError(f"radius: {rr:g} disagrees with |start - center| = {r:.12g}")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "normal", n)
        object.__setattr__(self, "start_point", s)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "duration", _positive(self.duration, "duration", "s"))
        object.__setattr__(self, "turns", _positive(self.turns, "turns", "revolutions"))
        TimeLaw(self.time_law)  # type: ignore[arg-type]

    @classmethod
    def from_start(cls, start: ArrayLike, radius: float, normal: ArrayLike,
                   toward: ArrayLike, **kwargs: object) -> Circle:
        """Circle through ``start`` whose centre lies ``radius`` away in direction ``toward``
        (projected into the plane of ``normal``)."""
        s = _vec3(start, "start")
        n = _vec3(normal, "normal")
        n = n / max(np.linalg.norm(n), 1e-300)
        d = _vec3(toward, "toward")
        d = d - (d @ n) * n
        if np.linalg.norm(d) < 1e-12:
            raise InputError("toward: must not be parallel to normal")
        r = _positive(radius, "radius", "length units")
        return cls(center=s + r * d / np.linalg.norm(d), normal=n, start_point=s, **kwargs)  # type: ignore[arg-type]

    def _evaluate(self, t: F64) -> tuple[F64, F64, F64]:
        r = float(self.radius)  # type: ignore[arg-type]
        e1 = (self.start_point - self.center) / r
        e2 = np.cross(self.normal, e1)
        s, ds, dds = TimeLaw(self.time_law)(t / self.duration)  # type: ignore[arg-type]
        k = 2.0 * np.pi * self.turns
        phi, dphi, ddphi = k * s, k * ds / self.duration, k * dds / self.duration**2
        c, sn = np.cos(phi)[:, None], np.sin(phi)[:, None]
        radial = c * e1 + sn * e2
        tangent = -sn * e1 + c * e2
        p = self.center + r * radial
        v = r * dphi[:, None] * tangent
        a = r * ddphi[:, None] * tangent - r * dphi[:, None] ** 2 * radial
        return p, v, a


@dataclass(frozen=True, eq=False)
class Line(Trajectory):
    """Straight line from ``start_point`` to ``end`` (shape (3,)) with a time law at rest."""

    start_point: F64
    end: F64
    duration: float = 2.0
    time_law: str = "quintic"
    orientation: OrientationLaw | None = field(default=None)

    def __post_init__(self) -> None:
        object.__setattr__(self, "start_point", _vec3(self.start_point, "start"))
        object.__setattr__(self, "end", _vec3(self.end, "end"))
        object.__setattr__(self, "duration", _positive(self.duration, "duration", "s"))
        TimeLaw(self.time_law)  # type: ignore[arg-type]

    def _evaluate(self, t: F64) -> tuple[F64, F64, F64]:
        s, ds, dds = TimeLaw(self.time_law)(t / self.duration)  # type: ignore[arg-type]
        d = self.end - self.start_point
        return (self.start_point + s[:, None] * d, (ds / self.duration)[:, None] * d,
                (dds / self.duration**2)[:, None] * d)


@dataclass(frozen=True, eq=False)
class FunctionTrajectory(Trajectory):
    """Any user function of time.

    Attributes:
        position: ``t (m,) -> (m, 3)``.
        duration: s.
        velocity, acceleration: optional ``t (m,) -> (m, 3)``; when absent they are taken by
            central differences of ``position`` with step ``fd_step`` (s) (error O(step^2)).
        orientation: optional orientation law (default: held at its start value).
    """

    position: Callable[[F64], ArrayLike]
    duration: float = 1.0
    velocity: Callable[[F64], ArrayLike] | None = None
    acceleration: Callable[[F64], ArrayLike] | None = None
    orientation: OrientationLaw | None = None
    fd_step: float = 1e-4

    def __post_init__(self) -> None:
        if not callable(self.position):
            raise InputError("position: expected a callable t (m,) -> (m, 3)")
        object.__setattr__(self, "duration", _positive(self.duration, "duration", "s"))

    def _call(self, fn: Callable[[F64], ArrayLike], t: F64, name: str) -> F64:
        try:
            out = np.asarray(fn(t), dtype=float)
        except Exception as exc:  # user code: say which function failed
            raise InputError(f"{name}: the user function raised {exc!r}") from exc
        if out.shape != (t.size, 3):
            raise InputError(f"{name}: expected shape ({t.size}, 3) for {t.size} times, got "
                             f"{out.shape}")
        bad = ~np.all(np.isfinite(out), axis=1)
        if bad.any():
            raise InputError(f"{name}: non-finite value at t = {t[np.argmax(bad)]:g} s")
        return out

    def _evaluate(self, t: F64) -> tuple[F64, F64, F64]:
        p = self._call(self.position, t, "position")
        h = self.fd_step
        if self.velocity is not None:
            v = self._call(self.velocity, t, "velocity")
        else:
            v = (self._call(self.position, t + h, "position")
                 - self._call(self.position, t - h, "position")) / (2 * h)
        if self.acceleration is not None:
            a = self._call(self.acceleration, t, "acceleration")
        else:
            a = (self._call(self.position, t + h, "position") - 2 * p
                 + self._call(self.position, t - h, "position")) / h**2
        return p, v, a
