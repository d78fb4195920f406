"""The commanded trajectories of the studies and the command line, built here and passed to the
robot (:mod:`sim.robot` never imports the paper):

* ``circle``: the paper's 125 mm PUMA circle (:func:`zrp.puma_circle`, 4 s, quintic time law):
  as poses evenly spaced along it (:func:`circle_poses`, the static measurement) or as its
  inverse-kinematics joints, a cubic spline with 0.5 s at rest before and after
  (:func:`circle_command`, the robot in motion);
* ``moves``: random rest-to-rest joint moves with dwells (:func:`zrp.gap.motion.paths.
  exercise_moves`): high speed, acceleration, stops and reversals on every joint.

:func:`measure_stream` executes a named trajectory on the real robot in motion
(``zrp measure --stream``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mjcf.own_dynamics import ArmDynamics
from sim.robot.instrument import random_instrument
from sim.robot.measurement import trajectory_poses
from sim.robot.motion import MotionRun, execute_trajectory
from sim.robot.motion_measure import Command, parse_motion_effects, spline_command
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.motion.paths import exercise_moves
from zrp.kinematics.ik import track_trajectory
from zrp.model.manipulator import Manipulator
from zrp.paper.scenario import puma_circle

__all__ = ["TRAJECTORIES", "circle_command", "circle_poses", "measure_stream",
           "named_command"]

TRAJECTORIES = ("circle", "moves")


def circle_poses(model: Manipulator, count: int) -> F64:
    """``count`` poses evenly spaced in time along the paper's 125 mm circle of the PUMA
    (:func:`zrp.puma_circle`), solved by the nominal inverse kinematics, rad, shape
    (count, n) (:func:`sim.robot.measurement.trajectory_poses`)."""
    if model.n != 6:
        raise InputError(f"trajectory 'circle' is the PUMA's; the model {model.name!r} has "
                         f"{model.n} joints")
    setup = puma_circle(model)
    return trajectory_poses(model, count, setup.trajectory, setup.q0)


def circle_command(model: Manipulator) -> tuple[Command, float]:
    """The paper's PUMA circle as a commanded trajectory (1000 inverse-kinematics steps as a
    clamped cubic spline, 0.5 s at rest before and after) and its duration, s."""
    if model.n != 6:
        raise InputError("trajectory: 'circle' is the PUMA circle; it needs a 6-joint model")
    setup = puma_circle(model)
    res = track_trajectory(setup.model, setup.trajectory, setup.q0, steps=1000)
    return spline_command(res.q, setup.trajectory.duration)


def named_command(model: Manipulator, name: str, rng: np.random.Generator, moves: int = 10
                  ) -> tuple[Command, float]:
    """The commanded trajectory ``name`` (see the module doc) and its duration, s."""
    if name == "moves":
        q0 = np.radians([0, -20, 30, 0, 60, 0]) if model.n == 6 else np.zeros(model.n)
        mv = exercise_moves(q0, rng, moves=moves)
        return mv, mv.duration
    if name == "circle":
        return circle_command(model)
    raise InputError(f"trajectory: {name!r}; expected one of {', '.join(TRAJECTORIES)}")


def measure_stream(model: Manipulator, trajectory: str, specs: Sequence[str], rate_hz: float,
                   noise_sigma: float, seed: int, field: str = "specs",
                   dynamics: ArmDynamics | None = None) -> MotionRun:
    """Execute the named trajectory on the real robot with the hidden effects ``specs`` and
    stream time-stamped tracker points at ``rate_hz`` (seeded instrument frame and noise).
    ``dynamics``: the arm's own (:func:`mjcf.arm_dynamics`; None: the announced fallback)."""
    effects = parse_motion_effects(specs, model, field)
    rng = np.random.default_rng(seed)
    command, duration = named_command(model, trajectory, rng)
    inst = random_instrument(model, rng, noise_sigma)
    return execute_trajectory(model, command, duration, effects, inst, rng, rate_hz=rate_hz,
                              dynamics=dynamics)
