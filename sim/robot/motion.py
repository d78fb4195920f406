"""The MuJoCo "real" robot in motion: it executes a joint trajectory with its servos and a
tracker streams time-stamped tool points (what ``zrp.gap.motion`` diagnoses).

The controller runs at the simulation step (1 ms): each step it feeds every servo (the
position + rate actuators of :class:`sim.RealRobot`) the reference, its rate, and the
rigid-body inverse-dynamics torque of the reference (``mj_inverse`` on a constraint-free copy
of the robot: computed-torque feedforward), so the nominal robot follows its command to a few
micrometres. Hidden motion effects (:class:`MotionEffects`) that emerge from the simulation:

* ``servo_lag`` (s, per joint): the controller passes the joint's command through a first-order
  filter (time constant tau) before the servo (a smoothed setpoint, as many drives do);
* ``reversal_friction`` (N m, per joint): Coulomb friction on the joint (MuJoCo
  ``frictionloss``), which the feedforward does not know and the servo (stiffness kp, no
  integral action on that joint) resists only by its error: the joint sticks at reversals and
  lags by F/kp while moving;
* ``dynamic_compliance`` (rad/(N m), per joint): the joint's servo stiffness is 1/c with no
  feedforward and no integral action, so it deflects by c times the full dynamic torque
  (gravity and inertia) it carries;
* ``residual_vibration`` (Hz, per joint; damping ratio ``vibration_damping``, default 0.05): a
  compliant transmission: the joint's link hangs on the stiffly servoed motor through a
  spring-damper tuned to that frequency and damping for the inertia the joint sees (its
  diagonal mass-matrix entry, re-evaluated each step), and the feedforward of that joint
  lacks its own inertial torque (the motor side does not carry it): the link lags under
  acceleration and rings after each stop (applied as the joint torque M_kk [omega^2 (ref - q)
  + 2 zeta omega (rate - q') - ref''] + the rest of the inverse-dynamics torque; the joint's
  position and rate actuators are switched off);
* ``sync_delay`` (s): the tracker's clock runs ahead of the controller's: a point measured at
  controller time T is stamped T + delta; the logged command is the controller's at the stamp.

Units: joint values rad, points in the model's length unit, time s.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
from scipy import signal

from mjcf.own_dynamics import ArmDynamics
from sim.robot.effects import HiddenEffects
from sim.robot.instrument import Instrument
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.motion.data import Trajectory
from zrp.model.manipulator import Manipulator

__all__ = ["MOTION_HIDDEN", "MotionEffects", "MotionRun", "execute_trajectory"]

MOTION_HIDDEN = ("sync_delay", "servo_lag", "reversal_friction", "dynamic_compliance",
                 "residual_vibration")


def _joints(v: Mapping[int, float] | None, name: str, unit: str) -> dict[int, float]:
    out = {}
    for k, x in dict(v or {}).items():
        x = float(x)
        if not (np.isfinite(x) and x > 0):
            raise InputError(f"{name}: joint {k}: expected a value > 0 ({unit}), got {x!r}")
        out[int(k)] = x
    return out


@dataclass(frozen=True)
class MotionEffects:
    """Hidden motion effects (all off by default); joint keys are 1-based.

    Attributes:
        sync_delay: tracker clock ahead of the controller's, s.
        servo_lag: per joint, first-order setpoint filter time constant, s.
        reversal_friction: per joint, Coulomb friction, N m.
        dynamic_compliance: per joint, rad/(N m) (servo stiffness 1/c, no feedforward).
        residual_vibration: per joint, the transmission mode's natural frequency, Hz.
        vibration_damping: the modes' damping ratio, in (0, 1).
    """

    sync_delay: float = 0.0
    servo_lag: Mapping[int, float] = field(default_factory=dict)
    reversal_friction: Mapping[int, float] = field(default_factory=dict)
    dynamic_compliance: Mapping[int, float] = field(default_factory=dict)
    residual_vibration: Mapping[int, float] = field(default_factory=dict)
    vibration_damping: float = 0.05

    def __post_init__(self) -> None:
        if not 0.0 < self.vibration_damping < 1.0:
            raise InputError(f"vibration_damping: expected a damping ratio in (0, 1), got "
                             f"{self.vibration_damping!r}")
        if not np.isfinite(self.sync_delay) or abs(self.sync_delay) > 0.1:
            raise InputError(f"sync_delay: expected |delta| <= 0.1 s, got {self.sync_delay!r}")
        object.__setattr__(self, "servo_lag", _joints(self.servo_lag, "servo_lag", "s"))
        object.__setattr__(self, "reversal_friction",
                           _joints(self.reversal_friction, "reversal_friction", "N m"))
        object.__setattr__(self, "dynamic_compliance",
                           _joints(self.dynamic_compliance, "dynamic_compliance", "rad/(N m)"))
        object.__setattr__(self, "residual_vibration",
                           _joints(self.residual_vibration, "residual_vibration", "Hz"))

    @property
    def active(self) -> tuple[str, ...]:
        return tuple(e for e in MOTION_HIDDEN if (self.sync_delay != 0.0 if e == "sync_delay"
                                                  else bool(getattr(self, e))))

    def joints(self, effect: str) -> tuple[int, ...]:
        """The joints of ``effect`` ((0,) for the sync delay)."""
        if effect == "sync_delay":
            return (0,) if self.sync_delay else ()
        return tuple(sorted(getattr(self, effect)))

    def to_dict(self) -> dict[str, Any]:
        return {"sync_delay": self.sync_delay,
                **{e: {str(k): v for k, v in getattr(self, e).items()}
                   for e in MOTION_HIDDEN[1:]},
                "vibration_damping": self.vibration_damping}


@dataclass(frozen=True, eq=False)
class MotionRun:
    """A simulated trajectory measurement.

    Attributes:
        trajectory: what the tracker and controller log (the diagnosis's input).
        q_actual: true joint values at the true measurement times, shape (S, n).
        effects: the hidden effects; instrument: the tracker.
        truth: the build and the effects, for the truth file.
    """

    trajectory: Trajectory
    q_actual: F64
    effects: MotionEffects
    instrument: Instrument
    truth: dict[str, Any]


def _robot(model: Manipulator, eff: MotionEffects, dynamics: ArmDynamics | None
           ) -> tuple[RealRobot, mujoco.MjModel]:
    robot = RealRobot(model, HiddenEffects(joint_compliance=dict(eff.dynamic_compliance)),
                      RealRobotOptions(timestep=1e-3, dynamics=dynamics))
    ff = copy.deepcopy(robot.model)
    m = robot.model
    for k, f in eff.reversal_friction.items():
        dof = robot._ids["motor_v"][k - 1]
        m.dof_frictionloss[dof] = f
        # a hard friction constraint (MuJoCo's default solref of 20 ms makes it viscous-like)
        m.dof_solref[dof] = [2.0 * m.opt.timestep, 1.0]
        m.dof_solimp[dof] = [0.99999, 0.99999, 0.001, 0.5, 2.0]
        robot._ids["trim"][k - 1] = False  # no integral action: the servo resists by its error
    n = model.n
    for k in eff.residual_vibration:  # the transmission spring replaces the joint's servo
        m.actuator_gainprm[k - 1, 0] = m.actuator_biasprm[k - 1, 1] = 0.0
        m.actuator_gainprm[n + k - 1, 0] = m.actuator_biasprm[n + k - 1, 2] = 0.0
        robot._ids["trim"][k - 1] = False
    return robot, ff


def _transmission(eff: MotionEffects, ff: mujoco.MjModel, dff: mujoco.MjData, dofs: F64,
                  reference: tuple[F64, F64, F64], q: F64, qd: F64, tau: F64) -> F64:
    """The joint torques with the transmission modes (see the module doc): ``tau`` (the
    feedforward, shape (n,)) with each vibrating joint's entry replaced; ``reference`` holds
    the reference angle, rate and acceleration, shape (n,) each."""
    ref, rate, acc = reference
    out = np.array(tau)
    z = eff.vibration_damping
    full = np.zeros((ff.nv, ff.nv))
    mujoco.mj_fullM(ff, dff, full)  # mj_inverse has just computed the mass matrix at ref
    for k, f in eff.residual_vibration.items():
        i = k - 1
        w = 2.0 * np.pi * f
        mkk = full[dofs[i], dofs[i]]
        out[i] = dff.qfrc_inverse[dofs[i]] + mkk * (w * w * (ref[i] - q[i])
                                                     + 2.0 * z * w * (rate[i] - qd[i]) - acc[i])
    return out


def _references(command: Callable[[F64, int], F64], times: F64, lag: Mapping[int, float],
                n: int) -> F64:
    """The servo references at ``times`` (shape (T, n)): the command, through the exact
    first-order response (scipy ``lsim``, input linear between steps) on lagging joints."""
    u = np.asarray(command(times, 0), dtype=float)
    out = np.array(u)
    for k, tau in lag.items():
        sysm = (np.array([[-1.0 / tau]]), np.array([[1.0 / tau]]), np.array([[1.0]]),
                np.array([[0.0]]))
        out[:, k - 1] = signal.lsim(sysm, u[:, k - 1], times - times[0], X0=[u[0, k - 1]])[1]
    return out


def execute_trajectory(model: Manipulator, command: Callable[[F64, int], F64], duration: float,
                       effects: MotionEffects, instrument: Instrument, rng: np.random.Generator,
                       *, rate_hz: float = 1000.0, tool_point: F64 | None = None,
                       dynamics: ArmDynamics | None = None) -> MotionRun:
    """Run the real robot along ``command`` (a function of time and derivative order returning
    joint values/velocities/accelerations, shape (..., n)) for ``duration`` s and stream the
    first reflector (or ``tool_point``) at ``rate_hz`` (the simulation step must divide the
    tracker period). ``dynamics``: the arm's own (:func:`mjcf.arm_dynamics`); None: the
    physics robot's fallback, announced."""
    if not 1.0 <= rate_hz <= 1000.0:
        raise InputError(f"rate_hz: expected 1-1000 Hz, got {rate_hz!r}")
    robot, ff = _robot(model, effects, dynamics)
    ids = robot._ids
    n = model.n
    dt = robot.timestep
    every = max(1, round(1.0 / (rate_hz * dt)))
    steps = int(np.floor(duration / dt))
    times = np.arange(-1, steps + 2) * dt
    ref = _references(command, times, effects.servo_lag, n)
    s = robot.session(ref[1])
    s.sub, s.period = 1, dt
    s._gain = np.where(ids["trim"], ids["ki"] * dt, 0.0)
    d, m = s.d, robot.model
    d.qpos[ids["motor_q"]] = ref[1]
    d.qvel[ids["motor_v"]] = (ref[1] - ref[0]) / dt
    dff = mujoco.MjData(ff)
    ff.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    no_ff = np.zeros(n, dtype=bool)
    for k in effects.dynamic_compliance:
        no_ff[k - 1] = True
    site = ids["sites"][0]
    rec_t, pts, qact = [], [], []
    for i in range(1, steps + 1):
        # state at times[i]; references consistent with MuJoCo's semi-implicit Euler step
        # (v+ = v + dt a, q+ = q + dt v+): the reference is then followed exactly.
        rate = (ref[i] - ref[i - 1]) / dt
        acc = (ref[i + 1] - 2.0 * ref[i] + ref[i - 1]) / (dt * dt)
        dff.qpos[:], dff.qvel[:], dff.qacc[:] = ref[i], rate, acc
        mujoco.mj_inverse(ff, dff)
        # + dt kv acc: implicitfast integrates the rate servo's damping implicitly,
        # (M + dt kv) dv = dt f, so the feedforward carries that term too
        tau = np.where(no_ff, 0.0, dff.qfrc_inverse + dt * ids["kv"] * acc)
        if effects.residual_vibration:
            tau = _transmission(effects, ff, dff, ids["motor_v"], (ref[i], rate, acc),
                                d.qpos[ids["motor_q"]], d.qvel[ids["motor_v"]], tau)
        d.qfrc_applied[ids["motor_v"]] = tau
        s.ref, s.rate = ref[i], rate
        s._apply()
        mujoco.mj_step(m, d)
        # integral action on the error at the state's time (the step ends at times[i + 1])
        s.trim += s._gain * (ref[i + 1] - d.qpos[ids["motor_q"]])
        if i % every == 0:
            mujoco.mj_kinematics(m, d)
            rec_t.append(times[i + 1])
            pts.append(d.site_xpos[site] / robot.scale)
            qact.append(d.qpos[ids["motor_q"]].copy())
    T = np.array(rec_t)
    x = np.array(pts)
    if tool_point is not None:
        raise InputError("tool_point: only the robot's first reflector is streamed")
    x = x @ instrument.rotation.T + np.asarray(instrument.translation)
    x = x + rng.normal(0.0, instrument.noise_sigma, x.shape)
    stamps = T + effects.sync_delay
    traj = Trajectory(stamps, command(stamps, 0), x, ("smr1",), "instrument",
                      source="simulated trajectory")
    truth = {"effects": effects.to_dict(), "active": list(effects.active),
             "noise_sigma": instrument.noise_sigma, "rate_hz": rate_hz,
             "timestep_s": dt, "robot": robot.describe(),
             "instrument": {"rotvec": list(instrument.rotvec),
                            "translation": list(instrument.translation)}}
    return MotionRun(traj, np.array(qact), effects, instrument, truth)
