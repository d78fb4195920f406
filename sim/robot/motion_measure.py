"""Named commanded trajectories and hidden-effect specs for the real robot in motion
(``zrp measure --stream``, the motion benchmark).

Trajectories (functions of time and derivative order, :data:`Command`):

* ``circle``: the paper's 125 mm PUMA circle (:func:`zrp.puma_circle`, 4 s, quintic time law),
  its inverse-kinematics joints as a cubic spline, with 0.5 s at rest before and after;
* ``moves``: random rest-to-rest joint moves with dwells (:func:`zrp.gap.motion.paths.
  exercise_moves`): high speed, acceleration, stops and reversals on every joint.

Effect specs: ``sync_delay=2ms``, ``servo_lag:2=5ms``, ``reversal_friction:2=15Nm``,
``dynamic_compliance:3=20urad/Nm``, ``residual_vibration:2=8Hz`` (the transmission mode's
frequency; damping ratio 0.05, :class:`~sim.robot.motion.MotionEffects`) (units optional: s,
N m, rad/(N m), Hz by default).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from sim.robot.measurement import random_instrument
from sim.robot.motion import MOTION_HIDDEN, MotionEffects, MotionRun, execute_trajectory
from zrp.errors import InputError
from zrp.gap.motion.paths import exercise_moves
from zrp.kinematics.ik import track_trajectory
from zrp.model.manipulator import Manipulator
from zrp.paper.scenario import puma_circle

__all__ = ["TRAJECTORIES", "measure_stream", "named_command", "parse_motion_effects"]

F64 = NDArray[np.float64]
Command = Callable[[F64, int], F64]
TRAJECTORIES = ("circle", "moves")
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


def named_command(model: Manipulator, name: str, rng: np.random.Generator, moves: int = 10
                  ) -> tuple[Command, float]:
    """The commanded trajectory ``name`` (see the module doc) and its duration, s."""
    if name == "moves":
        q0 = np.radians([0, -20, 30, 0, 60, 0]) if model.n == 6 else np.zeros(model.n)
        mv = exercise_moves(q0, rng, moves=moves)
        return mv, mv.duration
    if name == "circle":
        if model.n != 6:
            raise InputError("trajectory: 'circle' is the PUMA circle; it needs a 6-joint model")
        setup = puma_circle(model)
        res = track_trajectory(setup.model, setup.trajectory, setup.q0, steps=1000)
        pad = 0.5
        t = pad + np.linspace(0.0, setup.trajectory.duration, res.q.shape[0])
        sp = CubicSpline(t, res.q, axis=0, bc_type="clamped")
        q_end = res.q[-1]

        def circle(tt: F64, order: int = 0) -> F64:
            tt = np.asarray(tt, dtype=float)
            inside = (tt >= t[0]) & (tt <= t[-1])
            val = sp(np.clip(tt, t[0], t[-1]), order)
            if order:
                return np.where(inside[..., None], val, 0.0)
            return np.where((tt < t[0])[..., None], res.q[0],
                            np.where((tt > t[-1])[..., None], q_end, val))
        return circle, float(t[-1] + pad)
    raise InputError(f"trajectory: {name!r}; expected one of {', '.join(TRAJECTORIES)}")


def measure_stream(model: Manipulator, trajectory: str, specs: Sequence[str], rate_hz: float,
                   noise_sigma: float, seed: int, field: str = "specs") -> MotionRun:
    """Execute the named trajectory on the real robot with the hidden effects ``specs`` and
    stream time-stamped tracker points at ``rate_hz`` (seeded instrument frame and noise)."""
    effects = parse_motion_effects(specs, model, field)
    rng = np.random.default_rng(seed)
    command, duration = named_command(model, trajectory, rng)
    inst = random_instrument(model, rng, noise_sigma)
    return execute_trajectory(model, command, duration, effects, inst, rng, rate_hz=rate_hz)
