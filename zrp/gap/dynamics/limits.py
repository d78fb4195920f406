"""The limits a joint command must meet before a robot plays it, and the one check of a
command against them (:func:`check_command_limits`): every sample's position, velocity,
acceleration and model torque.

A command is a table of samples (t, q), as a robot's controller plays it. Its velocities and
accelerations are checked twice where the command's own (analytic) values are known: those
values at every sample, and the divided differences of the positions as written (what a
controller differentiating the samples sees; by the mean-value theorem they lie within the
range of the true derivatives, so a smooth command within its limits passes them; the check
allows only the rounding of the divided differences themselves, a few units in the last
place of the positions over the time step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["JointLimits", "check_command_limits", "check_within_positions"]

_EPS = float(np.finfo(float).eps)


def _vector(value: object, n: int, field: str) -> F64:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise InputError(f"{field}: expected 1 or {n} values (one a joint), got shape {a.shape}")
    if np.isnan(a).any():
        k = int(np.argmax(np.isnan(a)))
        raise InputError(f"{field}: joint {k + 1} is nan; expected a number (inf: no limit)")
    return a


@dataclass(frozen=True)
class JointLimits:
    """What each joint may do, SI units (rad or m for slides), each shape (n,).

    Attributes:
        lower, upper: position limits (-inf/+inf where none).
        velocity: largest |qd| (inf where none known).
        acceleration: largest |qdd| (inf where none known).
        torque: largest |tau| of the model's inverse dynamics, N m or N (inf where none known).
        names: the joints' names (for errors).
        revolute: which joints are hinges (rad); the others slide (m).

    Raises:
        InputError: a NaN limit, lower > upper, a limit <= 0 or -inf (named by joint).
    """

    lower: F64
    upper: F64
    velocity: F64
    acceleration: F64
    torque: F64
    names: tuple[str, ...]
    revolute: NDArray[np.bool_]

    def __post_init__(self) -> None:
        n = len(self.names)
        lo, hi = np.asarray(self.lower, float), np.asarray(self.upper, float)
        for field, v, wrong in (("lower position limit", lo, np.inf),
                                ("upper position limit", hi, -np.inf)):
            if v.shape != (n,) or np.isnan(v).any() or np.any(v == wrong):
                raise InputError(f"{field}: expected {n} numbers (+-inf: none), got {v}")
        if np.any(lo > hi):
            k = int(np.argmax(lo > hi))
            raise InputError(f"position limits of joint {k + 1} ({self.names[k]}): lower "
                             f"{lo[k]:g} > upper {hi[k]:g}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        for field in ("velocity", "acceleration", "torque"):
            v = _vector(getattr(self, field), n, f"{field} limit")
            if np.any(v <= 0):
                k = int(np.argmax(v <= 0))
                raise InputError(f"{field} limit of joint {k + 1} ({self.names[k]}): "
                                 f"{v[k]:g}; expected > 0")
            object.__setattr__(self, field, v)
        object.__setattr__(self, "revolute", np.asarray(self.revolute, dtype=bool))

    @property
    def n(self) -> int:
        return len(self.names)

    def unit(self, k: int, per: str = "") -> str:
        """The unit of joint ``k``'s position (``per``: "/s", "/s^2"; "torque": N m or N)."""
        if per == "torque":
            return "N m" if self.revolute[k] else "N"
        return ("rad" if self.revolute[k] else "m") + per

    def joint(self, k: int) -> str:
        return f"joint {k + 1} ({self.names[k]})"


def check_within_positions(q: F64, limits: JointLimits, what: str) -> None:
    """Every row of ``q`` (S, n) within the position limits; else an InputError naming the
    joint, the row's ``what`` and the value."""
    out = (q < limits.lower) | (q > limits.upper)
    if out.any():
        i, k = (int(v) for v in np.argwhere(out)[0])
        u = limits.unit(k)
        raise InputError(f"{what}: {limits.joint(k)} reaches {q[i, k]:.6g} {u} at sample "
                         f"{i + 1}, outside its limits [{limits.lower[k]:.6g}, "
                         f"{limits.upper[k]:.6g}] {u}")


def _over(values: F64, limit: F64, tol: F64 | float, limits: JointLimits, what: str,
          label: str, t: F64 | None, per: str) -> None:
    bad = np.abs(values) > limit + tol
    if not bad.any():
        return
    i, k = (int(v) for v in np.argwhere(bad)[0])
    when = f"at t = {t[i]:.6g} s" if t is not None else f"at sample {i + 1}"
    u = limits.unit(k, per)
    raise InputError(f"{what}: {limits.joint(k)} {label} {values[i, k]:.6g} {u} {when}, "
                     f"beyond its limit {limit[k]:.6g} {u}")


def _times(t: F64, s: int, what: str) -> F64:
    t = np.asarray(t, dtype=float)
    if t.shape != (s,) or not np.all(np.isfinite(t)):
        raise InputError(f"{what}: expected {s} finite times, got shape {t.shape}")
    if s > 1 and not np.all(np.diff(t) > 0):
        raise InputError(f"{what}: the times must increase strictly")
    return t


def _differences(t: F64, q: F64, limits: JointLimits, what: str) -> None:
    """Divided differences of the written positions (module docstring)."""
    if len(t) < 2:
        return
    h = np.diff(t)[:, None]
    v = np.diff(q, axis=0) / h
    scale = np.maximum(np.abs(q).max(0), 1.0)
    _over(v, limits.velocity, 4 * _EPS * scale / h.min(), limits, what,
          "moves at (sample to sample)", t, "/s")
    if len(t) < 3:
        return
    a = 2.0 * np.diff(v, axis=0) / (t[2:] - t[:-2])[:, None]
    _over(a, limits.acceleration, 16 * _EPS * scale / h.min() ** 2, limits, what,
          "accelerates at (sample to sample)", t, "/s^2")


def check_command_limits(q: F64, limits: JointLimits, *, t: F64 | None = None,
                         qd: F64 | None = None, qdd: F64 | None = None, tau: F64 | None = None,
                         what: str = "command") -> None:
    """Check a joint command, every sample, against ``limits``; any command file a robot
    plays passes here before it is written.

    Args:
        q: the positions as they will be written (rad, m), shape (S, n).
        limits: the joints' limits.
        t: the samples' times, s (S,): the divided differences of ``q`` are checked against
            the velocity and acceleration limits (module docstring).
        qd, qdd: the command's own velocities and accelerations at the samples, (S, n).
        tau: the model's joint torques along the command, (S, n).
        what: what to name in an error (the file, the option).

    Raises:
        InputError: a non-finite value, or the first sample beyond a limit (joint, value,
            time or sample, limit).
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != limits.n:
        raise InputError(f"{what}: expected positions of shape (samples, {limits.n}), got "
                         f"{q.shape}")
    for label, arr in (("positions", q), ("velocities", qd), ("accelerations", qdd),
                       ("torques", tau)):
        if arr is not None and (np.shape(arr) != q.shape or not np.all(np.isfinite(arr))):
            raise InputError(f"{what}: {label} must be finite, shape {q.shape}")
    check_within_positions(q, limits, what)
    ts = None if t is None else _times(t, len(q), what)
    if qd is not None:
        _over(np.asarray(qd), limits.velocity, 0.0, limits, what, "moves at", ts, "/s")
    if qdd is not None:
        _over(np.asarray(qdd), limits.acceleration, 0.0, limits, what, "accelerates at", ts,
              "/s^2")
    if tau is not None:
        _over(np.asarray(tau), limits.torque, 0.0, limits, what, "needs a torque of", ts, "torque")
    if ts is not None:
        _differences(ts, q, limits, what)
