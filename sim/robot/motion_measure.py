"""Hidden-effect specs of the real robot in motion, and joint paths as commanded trajectories
(``zrp measure --stream``, the motion benchmark).

Effect specs: ``sync_delay=2ms``, ``servo_lag:2=5ms``, ``reversal_friction:2=15Nm``,
``dynamic_compliance:3=20urad/Nm``, ``residual_vibration:2=8Hz`` (the transmission mode's
frequency; damping ratio 0.05, :class:`~sim.robot.motion.MotionEffects`) (units optional: s,
N m, rad/(N m), Hz by default).

A commanded trajectory is a function of time and derivative order (:data:`Command`). Which
trajectory is the caller's choice (the named ones, e.g. the paper's PUMA circle, are built in
:mod:`sim.studies.trajectories`); :func:`spline_command` turns joint values sampled evenly in
time (e.g. the inverse kinematics of a Cartesian path) into one.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import CubicSpline

from sim.robot.motion import MOTION_HIDDEN, MotionEffects
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator

__all__ = ["Command", "parse_motion_effects", "spline_command"]

#: A commanded trajectory: ``command(t, order)`` -> joint values (order 0) or their time
#: derivative of that order at the times ``t``, shape (..., n).
Command = Callable[[F64, int], F64]
_UNITS = {"sync_delay": {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6},
          "servo_lag": {"": 1.0, "s": 1.0, "ms": 1e-3},
          "reversal_friction": {"": 1.0, "Nm": 1.0},
          "dynamic_compliance": {"": 1.0, "rad/Nm": 1.0, "mrad/Nm": 1e-3, "urad/Nm": 1e-6},
          "residual_vibration": {"": 1.0, "Hz": 1.0}}
_SPEC = re.compile(r"^([a-z_]+)(?::(\d+))?=([-+0-9.eE]+)\s*([A-Za-z/]*)$")


def parse_motion_effects(specs: Sequence[str], model: Manipulator, field: str = "specs"
                         ) -> MotionEffects:
    """Build :class:`~sim.robot.motion.MotionEffects` from ``NAME[:J]=VALUE[UNIT]`` strings."""
    delay = 0.0
    per: dict[str, dict[int, float]] = {e: {} for e in MOTION_HIDDEN[1:]}
    for spec in specs:
        m = _SPEC.match(spec.strip())
        if not m or m.group(1) not in MOTION_HIDDEN:
            raise InputError(f"{field} {spec!r}: expected NAME[:J]=VALUE[UNIT] with NAME one of "
                             f"{', '.join(MOTION_HIDDEN)}")
        name, joint, value, unit = m.groups()
        if unit not in _UNITS[name]:
            raise InputError(f"{field} {spec!r}: unit {unit!r}; expected one of "
                             f"{', '.join(u for u in _UNITS[name] if u)}")
        v = float(value) * _UNITS[name][unit]
        if name == "sync_delay":
            delay = v
            continue
        if joint is None or not 1 <= int(joint) <= model.n:
            raise InputError(f"{field} {spec!r}: {name} needs a joint 1..{model.n} (NAME:J=...)")
        per[name][int(joint)] = v
    return MotionEffects(delay, **per)


def spline_command(q: ArrayLike, duration: float, pad: float = 0.5) -> tuple[Command, float]:
    """Joint values ``q`` (shape (T, n)) sampled evenly over ``duration`` s as a commanded
    trajectory: a clamped cubic spline (at rest at both ends), held at rest ``pad`` s before
    and after. Returns the command and its total duration, s."""
    q = np.asarray(q, dtype=float)
    t = pad + np.linspace(0.0, duration, q.shape[0])
    sp = CubicSpline(t, q, axis=0, bc_type="clamped")
    q_end = q[-1]

    def command(tt: F64, order: int = 0) -> F64:
        tt = np.asarray(tt, dtype=float)
        inside = (tt >= t[0]) & (tt <= t[-1])
        val = sp(np.clip(tt, t[0], t[-1]), order)
        if order:
            return np.where(inside[..., None], val, 0.0)
        return np.where((tt < t[0])[..., None], q[0],
                        np.where((tt > t[-1])[..., None], q_end, val))
    return command, float(t[-1] + pad)
