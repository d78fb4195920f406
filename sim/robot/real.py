"""A "real" robot in MuJoCo: hidden effects that emerge from simulation, not from formulas.

:class:`RealRobot` builds a MuJoCo model of the physical robot behind a ZRP manipulator model
and drives it like a robot controller would: the user commands joint values, a position servo
per joint moves the arm, the arm settles under gravity, and the tool points are read. Effects
the nominal model does not know about, each switched on with a magnitude in
:class:`HiddenEffects` (names as in the gap diagnosis, :data:`zrp.gap.EFFECTS`):

* ``joint_offset``, ``encoder_scale``, ``cyclic_error`` (encoder/transmission errors): the
  controller's joint value q maps to the true motor angle q + o + s q + a sin(h q) + b cos(h q);
  the servo drives the motor there.
* ``link_length`` (body offsets) and ``axis_misalignment`` (tilted joint axes): the MuJoCo
  bodies and joint axes are those of a perturbed copy of the model (hidden geometric errors).
* ``joint_compliance``: the joint's position servo has a finite stiffness kp = 1/c (N m/rad)
  and no integral action, so gravity and the payload deflect the joint by tau/kp (rad). Joints
  without compliance have a servo with integral action (a setpoint trim), which settles the
  motor exactly on its target whatever the load.
* ``backlash``: the joint is split into a motor-side hinge (driven by the servo, carrying the
  rotor inertia) and a load-side hinge (carrying the link) with a free play of b rad between
  them (a joint limit of +-b/2) and Coulomb friction of the load against its parent (a fixed
  tendon with ``frictionloss``). Approached slowly from one side, the load lags by b/2 behind
  the motor; a gravity torque larger than the friction pushes it onto the loaded flank instead.
* ``thermal_expansion``: every body vector (and centre of mass) scales by
  1 + alpha (T - t_ref) at the temperature T of the moment (deg C).
* ``payload``: a point mass (kg) at the end-effector point (it matters through the servo
  stiffness and the backlash).

Link inertias: the arm's own, from its shipped URDF/MJCF (``RealRobotOptions.dynamics``);
without them an announced fallback, the PUMA 560 literature values for a 6R arm, uniform rods
otherwise (:mod:`sim.robot.mass`). Servo gains are tuned from the arm's inertia over its
workspace (:mod:`sim.robot.servo`). The effects themselves are :mod:`sim.robot.effects`; the
MuJoCo model is assembled in :mod:`sim.robot.model` (layout as in :mod:`mjcf.builder`).

Units: joint values rad (model length unit for prismatic joints), positions in the model's
length unit in the API (MuJoCo works in metres inside), torques N m, masses kg, deg C.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf.inertia import BodyInertia
from sim.robot.effects import (
    HiddenEffects,
    default_tool_points,
    finite,
    freeze,
    motor_map,
    true_geometry,
)
from sim.robot.mass import link_inertias, robot_mass
from sim.robot.model import PUMA560_LOAD_FRICTION, RealRobotOptions, build_robot_model
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import forward_kinematics
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = ["Reading", "RealRobot", "Session"]



@dataclass(frozen=True, eq=False)
class Reading:
    """What the simulation shows once the arm has settled at one pose.

    Attributes:
        points: tool points in the robot's base frame, model length unit, shape (M, 3).
        q_link: true joint values of the links (load side), rad, shape (n,).
        q_motor: motor-side joint values, rad, shape (n,) (equal to q_link without backlash).
        motor_target: the true motor angles the servos were asked to reach, shape (n,).
        torque: static torque each servo carries (actuator force), N m, shape (n,).
        temperature: deg C at the reading.
        residual_speed: largest joint speed when read (rad/s), a settling check.
    """

    points: F64
    q_link: F64
    q_motor: F64
    motor_target: F64
    torque: F64
    temperature: float
    residual_speed: float




class RealRobot:
    """The MuJoCo "real" robot of a nominal model with :class:`HiddenEffects`.

    Args:
        model: the nominal ZRP model (what the user believes).
        effects: what the real robot hides.
        options: build and drive options.

    Use :meth:`session` to drive it (the measuring procedure in :mod:`sim.robot.measurement` does).
    """

    def __init__(self, model: Manipulator, effects: HiddenEffects | None = None,
                 options: RealRobotOptions | None = None) -> None:
        if not isinstance(model, Manipulator):
            raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
        self.nominal = model
        self.effects = effects or HiddenEffects()
        if not isinstance(self.effects, HiddenEffects):
            raise InputError(f"effects: expected sim.robot.effects.HiddenEffects, got "
                             f"{type(self.effects).__name__}")
        self.effects.check(model)
        self.options = options or RealRobotOptions()
        n = model.n
        self.n = n
        self.scale = metres_per_unit(model.length_unit, "model.length_unit")
        self.true_model = self._true_geometry()
        tp = (default_tool_points(model) if self.options.tool_points is None
              else np.asarray(self.options.tool_points, dtype=float))
        self.tool_points = freeze(tp)
        self.mass = robot_mass(model, self.options)
        if self.options.dynamics is not None and len(self.options.dynamics.inertias) != n:
            raise InputError(f"dynamics: {len(self.options.dynamics.inertias)} links, but the "
                             f"model has {n} joints")
        fr = self.options.load_friction
        if fr is None:
            fr = PUMA560_LOAD_FRICTION if self.mass.kind == "puma560" else (1.0,) * n
        if len(fr) != n:
            raise InputError(f"load_friction: expected {n} values (one per joint), got {len(fr)}")
        self.load_friction = freeze(fr)
        self.model, self._ids = self._build()

    # ---- construction ---------------------------------------------------------------------
    def _true_geometry(self) -> Manipulator:
        return true_geometry(self.nominal, self.effects)

    def _inertias(self) -> list[BodyInertia]:
        return link_inertias(self.mass, self.true_model, self.options, self.scale)


    def _build(self) -> tuple[mujoco.MjModel, dict[str, Any]]:
        return build_robot_model(self.true_model, self.effects, self._inertias(),
                                 self.tool_points, self.load_friction, self.scale, self.options)

    # ---- the controller's view ------------------------------------------------------------
    @property
    def timestep(self) -> float:
        """Simulation step, s."""
        return float(self.model.opt.timestep)

    @property
    def servo_stiffness(self) -> F64:
        """kp per joint, N m/rad, shape (n,)."""
        return freeze(self._ids["kp"])

    def motor_target(self, q: ArrayLike) -> F64:
        """True motor angles for controller joint values ``q`` (rad), shape (..., n) -> same.

        Applies the encoder/transmission errors: q + offset + s q + a sin(h q) + b cos(h q).
        """
        return motor_map(self.effects, q)

    def thermal_scale(self, temperature: float) -> float:
        """1 + alpha (T - t_ref): the factor on every body vector at ``temperature`` deg C."""
        return 1.0 + self.effects.thermal_expansion * (float(temperature) - self.options.t_ref)

    def session(self, q_start: ArrayLike, temperature: float | None = None) -> Session:
        """A fresh simulation with the arm at rest at controller joint values ``q_start``."""
        return Session(self, q_start, self.options.t_ref if temperature is None else temperature)

    def kinematic_points(self, q_link: ArrayLike, temperature: float | None = None) -> F64:
        """Tool points of the true geometry at true link angles (no dynamics), model unit,
        shape (..., M, 3); used to check the simulation against kinematics."""
        s = self.thermal_scale(self.options.t_ref if temperature is None else temperature)
        tm = self.true_model.with_arrays(bodies=np.asarray(self.true_model.bodies) * s)
        fk = forward_kinematics(tm, q_link)
        return fk.position[..., None, :] + np.einsum("...ij,mj->...mi", fk.rotation,
                                                     self.tool_points)

    def static_torque(self, q: ArrayLike) -> F64:
        """Torque each servo must supply to hold the arm at rest at joint values ``q`` (rad,
        model unit for prismatic joints), N m (N), shape (P, n): MuJoCo's ``qfrc_bias`` of
        the motor-side joints with the load hinges (if any) at the middle of their play and
        the geometry at t_ref. Positive: gravity would turn the joint negatively."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if q.shape[-1] != self.n:
            raise InputError(f"q: expected shape (P, {self.n}), got {q.shape}")
        d = mujoco.MjData(self.model)
        ids = self._ids
        qs = np.where(self.true_model.prismatic, self.scale, 1.0)
        out = np.empty(q.shape)
        for i, qi in enumerate(q):
            d.qpos[ids["motor_q"]] = qi * qs
            mujoco.mj_forward(self.model, d)
            out[i] = d.qfrc_bias[ids["motor_v"]]
        return out

    def describe(self) -> dict[str, Any]:
        """The build (servo gains, time step, friction, inertias; the arm's own file and its
        SHA-256 when its dynamics came from one) for the truth file."""
        return {"timestep_s": self.timestep, "servo_kp_Nm_per_rad": self._ids["kp"].tolist(),
                "servo_kv_Nms_per_rad": self._ids["kv"].tolist(),
                "integral_trim": self._ids["trim"].tolist(),
                "load_friction_Nm": self.load_friction.tolist(),
                "inertia": self.mass.kind, "dynamics": self.mass.note,
                "dynamics_fallback": self.mass.fallback, "t_ref_degC": self.options.t_ref,
                "tool_points": self.tool_points.tolist(),
                "true_axes": np.asarray(self.true_model.axes).tolist(),
                "true_bodies": np.asarray(self.true_model.bodies).tolist(),
                "gravity_m_s2": list(self.options.gravity), **self._arm_file()}

    def _arm_file(self) -> dict[str, str]:
        """The arm's own file the dynamics came from (absolute path, SHA-256), if any."""
        dyn = self.options.dynamics
        if dyn is None:
            return {}
        return {"arm_file": os.path.abspath(dyn.source), "arm_sha256": dyn.sha256}


class Session:
    """One run of the real robot: move, settle, read (see :meth:`RealRobot.session`).

    Each joint's servo is a position actuator (stiffness kp) plus a rate actuator (damping kv)
    on the motor-side joint, fed every ``control_period`` with the reference angle
    ``ref + trim`` and the reference rate. ``trim`` is the integral action of the joints
    without compliance: trim += ki dt (ref - motor angle), so their motors settle exactly on
    the target whatever load they carry; joints with compliance have no integral action and
    settle short by tau/kp.
    """

    def __init__(self, robot: RealRobot, q_start: ArrayLike, temperature: float,
                 control_period: float = 4e-3) -> None:
        self.robot = robot
        m = robot.model
        self.d = mujoco.MjData(m)
        self.ids = robot._ids
        self.n = robot.n
        self.temperature = float("nan")
        self.set_temperature(temperature)
        q0 = robot.motor_target(np.asarray(q_start, dtype=float))
        self._q_scale = np.where(robot.true_model.prismatic, robot.scale, 1.0)
        self.ref = q0 * self._q_scale
        self.rate = np.zeros(self.n)
        self.trim = np.zeros(self.n)
        self.d.qpos[self.ids["motor_q"]] = self.ref
        self.time = 0.0
        self.sub = max(1, round(control_period / robot.timestep))
        self.period = self.sub * robot.timestep
        self._gain = np.where(self.ids["trim"], self.ids["ki"] * self.period, 0.0)
        self._apply()
        mujoco.mj_forward(m, self.d)

    def set_temperature(self, temperature: float) -> None:
        """Scale the body vectors for ``temperature`` (deg C) (thermal growth of the links)."""
        t = finite(temperature, "temperature", "deg C")
        if t == self.temperature:
            return
        self.temperature = t
        r = self.robot
        s = r.thermal_scale(t)
        m = r.model
        ids = self.ids
        m.body_pos[ids["pos_bodies"]] = ids["body_pos0"] * s
        m.body_ipos[ids["link_bodies"]] = ids["body_ipos0"] * s
        tip = ids["tip_m"]
        m.site_pos[:] = ids["site_pos0"] + (s - 1.0) * tip
        if ids["payload"] >= 0:
            m.body_pos[ids["payload"]] = tip * s

    def _apply(self) -> None:
        n = self.n
        self.d.ctrl[:n] = self.ref + self.trim
        self.d.ctrl[n:] = self.rate

    def _period(self) -> F64:
        """Advance one control period; update the integral action; return the motor error."""
        mujoco.mj_step(self.robot.model, self.d, nstep=self.sub)
        self.time += self.period
        err = self.ref - self.d.qpos[self.ids["motor_q"]]
        self.trim += self._gain * err
        return err

    def move(self, q_to: ArrayLike, duration: float) -> None:
        """Move the servo references from where they are to controller joint values ``q_to``
        (rad) along a quintic (rest to rest) in ``duration`` s, with rate feedforward."""
        dur = finite(duration, "duration", "s")
        if dur <= 0:
            raise InputError(f"duration: expected a time > 0 s, got {duration!r}")
        r = self.robot
        target = r.motor_target(np.asarray(q_to, dtype=float)) * self._q_scale
        start = self.ref.copy()
        delta = target - start
        periods = max(1, math.ceil(dur / self.period))
        T = periods * self.period
        # the loop of _apply + _period written out with local names (the same arithmetic:
        # Python's overhead per control period was a quarter of the simulation's time)
        m, d, n, sub, per = r.model, self.d, self.n, self.sub, self.period
        ctrl, qpos, mq, gain, trim = d.ctrl, d.qpos, self.ids["motor_q"], self._gain, self.trim
        step = mujoco.mj_step
        for i in range(1, periods + 1):
            s = i / periods
            ref = start + (s**3 * (10 - 15 * s + 6 * s * s)) * delta
            ctrl[:n] = ref + trim
            ctrl[n:] = (30 * s * s * (1 - s) ** 2 / T) * delta
            step(m, d, nstep=sub)
            self.time += per
            trim += gain * (ref - qpos[mq])
        self.ref = target
        self.rate = np.zeros(self.n)
        self._apply()

    def jump(self, q_to: ArrayLike, duration: float) -> None:
        """Put the motors at rest on the targets of controller joint values ``q_to`` without
        simulating the way there; the clock advances by ``duration`` s (whole control periods)
        as if the move had been made. The load hinges keep their play and the integral trims
        their values; what follows (a slow approach, then :meth:`settle`) sets the flanks and
        trims as it does after a simulated move."""
        dur = finite(duration, "duration", "s")
        if dur <= 0:
            raise InputError(f"duration: expected a time > 0 s, got {duration!r}")
        r = self.robot
        target = r.motor_target(np.asarray(q_to, dtype=float)) * self._q_scale
        d = self.d
        d.qpos[self.ids["motor_q"]] = target
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        self.ref = target
        self.rate = np.zeros(self.n)
        self._apply()
        mujoco.mj_forward(r.model, d)
        periods = max(1, math.ceil(dur / self.period))
        self.time += periods * self.period
        d.time += periods * self.period

    def settle(self, max_time: float = 2.0, check_every: float = 0.04, tol_rad: float = 1e-7,
               speed_tol: float = 1e-5) -> float:
        """Hold the references until the motors with integral action are within ``tol_rad``
        of their targets and no joint moves faster than ``speed_tol`` (rad/s), or
        ``max_time`` s passed. Returns the final largest joint speed (rad/s)."""
        every = max(1, round(check_every / self.period))
        mask = self.ids["trim"]
        speed = math.inf
        elapsed = 0.0
        m, d, n, sub, per = self.robot.model, self.d, self.n, self.sub, self.period
        ctrl, qpos, mq, gain, trim = d.ctrl, d.qpos, self.ids["motor_q"], self._gain, self.trim
        ref = self.ref
        step = mujoco.mj_step
        err = np.zeros(n)
        while elapsed < max_time:
            for _ in range(every):  # _period then _apply, written out (see move)
                step(m, d, nstep=sub)
                self.time += per
                err = ref - qpos[mq]
                trim += gain * err
                ctrl[:n] = ref + trim
            elapsed += every * self.period
            speed = float(np.max(np.abs(self.d.qvel)))
            if np.max(np.abs(err[mask]), initial=0.0) < tol_rad and speed < speed_tol:
                break
        return speed

    def read(self, residual_speed: float = 0.0) -> Reading:
        """The settled state: tool points (base frame, model unit) and joint values."""
        r = self.robot
        m, d = r.model, self.d
        ids = self.ids
        motor = d.qpos[ids["motor_q"]] / self._q_scale
        link = motor.copy()
        has_play = ids["play_q"] >= 0
        link[has_play] += d.qpos[ids["play_q"][has_play]] / self._q_scale[has_play]
        mujoco.mj_forward(m, d)
        pts = d.site_xpos[ids["sites"]] / r.scale
        n = self.n
        torque = d.actuator_force[:n] + d.actuator_force[n:]
        return Reading(points=freeze(pts), q_link=freeze(link), q_motor=freeze(motor),
                       motor_target=freeze(self.ref / self._q_scale),
                       torque=freeze(torque), temperature=self.temperature,
                       residual_speed=float(residual_speed))
