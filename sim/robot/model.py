"""The MuJoCo model of the "real" robot: its build options and its assembly with MjSpec.

Layout as in :mod:`mjcf.builder`: body frames are world-aligned at q = 0, body k sits at
b_{k,0} (metres), joint k turns about u_{k,0}. Per joint a position servo (a position actuator,
stiffness kp, plus a rate actuator, damping kv) drives the motor-side joint; a joint with
``backlash`` is split into a motor hinge and a load hinge with a free play between them and
Coulomb friction of the load against its parent (a fixed tendon with ``frictionloss``); the
tool carries the reflector sites ``smr1..smrM`` and, with a payload, a point-mass body.
How the effects behave is described in :mod:`sim.robot.real`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from mjcf.inertia import BodyInertia
from mjcf.own_dynamics import ArmDynamics
from sim.robot.effects import HiddenEffects, finite
from sim.robot.servo import ServoGains, rotor_armature, tune_servos
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.sampling import default_limits
from zrp.model.manipulator import Manipulator

__all__ = ["PUMA560_LOAD_FRICTION", "RealRobotOptions", "build_robot_model"]


#: Coulomb friction of the load side of each PUMA 560 joint against its parent, N m: 20 % of
#: the drive's total Coulomb friction, i.e. of the motor-side values of Armstrong et al.
#: (1986) as tabulated by Corke & Armstrong-Hélouvry (1994) (0.395, 0.126, 0.132, 0.0112,
#: 0.00926, 0.00396 N m) times the gear ratios (62.6, 107.8, 53.7, 76.0, 71.9, 76.7). The
#: 20 % (bearing and output-stage share, our assumption) only matters inside the backlash: it
#: holds the load where the last slow approach left it unless gravity is stronger.
PUMA560_LOAD_FRICTION = (4.94, 2.72, 1.42, 0.170, 0.133, 0.0607)


@dataclass(frozen=True)
class RealRobotOptions:
    """How the real robot is built and driven.

    Attributes:
        inertia: "auto" (the arm's own inertias when ``dynamics`` is given; else the
            fallback, announced: PUMA 560 values for a 6R arm, rods otherwise), "own",
            "puma560" or "rods" (:mod:`sim.robot.mass`).
        dynamics: the arm's own mass properties, damping and friction, read from its shipped
            URDF/MJCF (:func:`mjcf.arm_dynamics`); needed by ``inertia="own"``.
        servo_bandwidth: omega of the servo tuning, rad/s (eqs S1-S5 of
            :mod:`sim.robot.servo`: kp = omega^2 max_q M_kk(q) for joints without compliance;
            their integral action removes the steady-state error whatever it is).
        damping_ratio: zeta of the servo tuning (:mod:`sim.robot.servo`).
        load_friction: Coulomb friction of each load-side hinge (backlash joints only), N m,
            shape (n,); None: :data:`PUMA560_LOAD_FRICTION` for the PUMA, 1 N m otherwise.
        tool_points: reflector offsets from the end-effector point, zero-reference base frame,
            model length unit, shape (M, 3); None: :func:`default_tool_points`.
        t_ref: temperature at which the geometry is the model's, deg C.
        gravity: m/s^2, shape (3,).
        timestep: s; None picks <= 1 ms from the stiffest servo.
    """

    inertia: str = "auto"
    dynamics: ArmDynamics | None = None
    servo_bandwidth: float = 150.0
    damping_ratio: float = 1.0
    load_friction: tuple[float, ...] | None = None
    tool_points: tuple[tuple[float, float, float], ...] | None = None
    t_ref: float = 20.0
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    timestep: float | None = None

    def __post_init__(self) -> None:
        if self.inertia not in ("auto", "own", "puma560", "rods"):
            raise InputError(f"inertia: {self.inertia!r}; expected 'auto', 'own', 'puma560' "
                             "or 'rods'")
        if self.dynamics is not None and not isinstance(self.dynamics, ArmDynamics):
            raise InputError(f"dynamics: expected mjcf.ArmDynamics, got "
                             f"{type(self.dynamics).__name__}")
        if self.inertia == "own" and self.dynamics is None:
            raise InputError("inertia: 'own' needs dynamics= (mjcf.arm_dynamics of the arm's "
                             "URDF/MJCF)")
        for name, unit in (("servo_bandwidth", "rad/s"), ("damping_ratio", "1")):
            object.__setattr__(self, name, _positive(getattr(self, name), name, unit))
        if self.load_friction is not None:
            object.__setattr__(self, "load_friction", _load_friction(self.load_friction))
        if self.tool_points is not None:
            object.__setattr__(self, "tool_points", _tool_points(self.tool_points))
        finite(self.t_ref, "t_ref", "deg C")
        object.__setattr__(self, "gravity", _gravity(self.gravity))
        if self.timestep is not None:
            _check_timestep(self.timestep)


def _positive(value: object, name: str, unit: str) -> float:
    v = finite(value, name, unit)
    if v <= 0:
        raise InputError(f"{name}: expected a value > 0 ({unit}), got {v!r}")
    return v


def _load_friction(value: Sequence[float]) -> tuple[float, ...]:
    f = np.asarray(value, dtype=float).ravel()
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise InputError(f"load_friction: expected finite values >= 0 (N m), got {value!r}")
    return tuple(float(x) for x in f)


def _tool_points(value: Sequence[Sequence[float]]) -> tuple[tuple[float, float, float], ...]:
    t = np.asarray(value, dtype=float)
    if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] < 1 or not np.all(np.isfinite(t)):
        raise InputError(f"tool_points: expected shape (M, 3) of finite numbers (model "
                         f"length unit), got {np.shape(value)}")
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in t)


def _gravity(value: Sequence[float]) -> tuple[float, float, float]:
    g = np.asarray(value, dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise InputError(f"gravity: expected 3 finite numbers (m/s^2), got {value!r}")
    return (float(g[0]), float(g[1]), float(g[2]))


def _check_timestep(value: float) -> None:
    dt = finite(value, "timestep", "s")
    if not 0 < dt <= 0.01:
        raise InputError(f"timestep: expected 0 < dt <= 0.01 s, got {value!r}")


@dataclass
class _Chain:
    """Names of the elements the chain builder added (motor joints, play joints, bodies)."""

    motor: list[str]
    play: list[str | None]
    links: list[str]
    positioned: list[str]  # the bodies whose position a thermal scaling moves


def _add_chain(spec: mujoco.MjSpec, tm: Manipulator, eff: HiddenEffects,
               inert: Sequence[BodyInertia], scale: float) -> tuple[_Chain, Any]:
    """Bodies and joints link1..linkn (motor + play hinges for a joint with backlash)."""
    bodies_m = np.asarray(tm.bodies) * scale
    axes = np.asarray(tm.axes)
    chain = _Chain([], [], [], [])
    parent = spec.worldbody
    for k in range(tm.n):
        kind = (mujoco.mjtJoint.mjJNT_SLIDE if tm.prismatic[k] else mujoco.mjtJoint.mjJNT_HINGE)
        ax = list(axes[k])
        if (k + 1) in eff.backlash:
            motor = parent.add_body(name=f"motor{k + 1}", pos=list(bodies_m[k]))
            motor.explicitinertial = True
            motor.mass = 1e-3
            motor.ipos = [0.0, 0.0, 0.0]
            motor.fullinertia = [1e-7, 1e-7, 1e-7, 0.0, 0.0, 0.0]
            mj = motor.add_joint(name=f"motor{k + 1}", axis=ax, type=kind)
            mj.armature = max(inert[k].armature, 1e-3)
            body = motor.add_body(name=f"link{k + 1}", pos=[0.0, 0.0, 0.0])
            half = 0.5 * eff.backlash[k + 1] * (scale if tm.prismatic[k] else 1.0)
            pj = body.add_joint(name=f"play{k + 1}", axis=ax, type=kind)
            pj.range = [-half, half]
            pj.armature = 1e-4
            chain.motor.append(f"motor{k + 1}")
            chain.play.append(f"play{k + 1}")
            chain.positioned.append(f"motor{k + 1}")
        else:
            body = parent.add_body(name=f"link{k + 1}", pos=list(bodies_m[k]))
            j = body.add_joint(name=f"q{k + 1}", axis=ax, type=kind)
            j.armature = max(inert[k].armature, 1e-3)
            chain.motor.append(f"q{k + 1}")
            chain.play.append(None)
            chain.positioned.append(f"link{k + 1}")
        body.explicitinertial = True
        body.mass = inert[k].mass
        body.ipos = list(inert[k].com)
        body.fullinertia = inert[k].fullinertia
        chain.links.append(f"link{k + 1}")
        parent = body
    return chain, parent


def _add_tool(spec: mujoco.MjSpec, last: Any, tip: F64, tool_points: F64, scale: float,
              payload: float) -> None:
    """The tool point, the reflector sites and the payload (a point mass) on the last link."""
    last.add_site(name="tool", pos=list(tip))
    for j, t in enumerate(tool_points):
        last.add_site(name=f"smr{j + 1}", pos=list(tip + np.asarray(t) * scale))
    if payload > 0:
        pl = last.add_body(name="payload", pos=list(tip))
        pl.explicitinertial = True
        pl.mass = payload
        pl.ipos = [0.0, 0.0, 0.0]
        r = 0.03
        i0 = 0.4 * payload * r * r
        pl.fullinertia = [i0, i0, i0, 0.0, 0.0, 0.0]


def _add_drives(spec: mujoco.MjSpec, chain: _Chain, load_friction: F64) -> None:
    """Bearing friction tendons of the play joints, then a position and a rate servo per joint
    (their gains are set by :func:`_tune` once the inertias are known)."""
    for k, name in enumerate(chain.play):
        if name is None:
            continue
        ten = spec.add_tendon(name=f"bearing{k + 1}")
        ten.frictionloss = float(load_friction[k])
        ten.wrap_joint(chain.motor[k], 1.0)
        ten.wrap_joint(name, 1.0)
    for k, name in enumerate(chain.motor):
        act = spec.add_actuator(name=f"servo{k + 1}", target=name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=1.0, kv=0.0)
    for k, name in enumerate(chain.motor):
        act = spec.add_actuator(name=f"servo{k + 1}_rate", target=name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_velocity(kv=1.0)


def _tune(spec: mujoco.MjSpec, chain: _Chain, effects: HiddenEffects,
          options: RealRobotOptions, lower: F64, upper: F64) -> ServoGains:
    """The servo gains and time step from the inertia each servo sees (eqs S1-S5 of
    :mod:`sim.robot.servo`; with the arm's own dynamics, its rotor inertias first, eq S0),
    set on the actuators; the play joints' limits and bearing friction get constraint time
    constants of 2 dt."""
    if options.dynamics is not None and options.inertia in ("auto", "own"):
        arm = rotor_armature(spec.compile(), chain.motor, options.dynamics.armature, lower,
                             upper)
        for name, a in zip(chain.motor, arm, strict=True):
            spec.joint(name).armature = float(a)
    gains = tune_servos(spec.compile(), chain.motor, effects.joint_compliance,
                        options.servo_bandwidth, options.damping_ratio, lower, upper,
                        options.timestep)
    dt = gains.timestep
    spec.option.timestep = dt
    for k, name in enumerate(chain.play):
        if name is not None:
            pj = spec.joint(name)
            pj.solref_limit = [2.0 * dt, 1.0]
            pj.solimp_limit = [0.9999, 0.9999, 0.001, 0.5, 2.0]
            ten = spec.tendon(f"bearing{k + 1}")
            ten.solref_friction = [2.0 * dt, 1.0]
            ten.solimp_friction = [0.99999, 0.99999, 0.001, 0.5, 2.0]
    for k in range(len(chain.motor)):
        spec.actuator(f"servo{k + 1}").set_to_position(kp=float(gains.kp[k]), kv=0.0)
        spec.actuator(f"servo{k + 1}_rate").set_to_velocity(kv=float(gains.kv[k]))
    return gains


def _joint_dynamics(spec: mujoco.MjSpec, chain: _Chain, dynamics: ArmDynamics | None) -> None:
    """The file's own viscous damping and Coulomb friction on the motor joints (where the file
    gives them)."""
    if dynamics is None:
        return
    for k, name in enumerate(chain.motor):
        j = spec.joint(name)
        j.damping = [float(dynamics.damping[k]), 0.0, 0.0]  # linear term only
        j.frictionloss = float(dynamics.friction[k])


def build_robot_model(true_model: Manipulator, effects: HiddenEffects,
                      inertias: Sequence[BodyInertia], tool_points: F64, load_friction: F64,
                      scale: float, options: RealRobotOptions
                      ) -> tuple[mujoco.MjModel, dict[str, Any]]:
    """Compile the real robot's MuJoCo model.

    Args:
        true_model: the real geometry (:func:`sim.robot.effects.true_geometry`).
        effects: the hidden effects (compliance, backlash and payload shape the model).
        inertias: mass properties per link (metres).
        tool_points: reflector offsets from the end-effector point, model unit, shape (M, 3).
        load_friction: Coulomb friction of each load hinge, N m, shape (n,).
        scale: metres per model length unit.
        options: servo bandwidth, damping ratio, the file's joint damping and friction,
            gravity, time step.

    Returns:
        the compiled model and the indices, gains and reference positions the controller
        (:class:`sim.robot.real.Session`) uses.
    """
    n = true_model.n
    spec = mujoco.MjSpec()
    spec.modelname = "real_robot"
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    spec.option.gravity = list(options.gravity)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    chain, last = _add_chain(spec, true_model, effects, inertias, scale)
    tip = np.asarray(true_model.bodies)[n] * scale
    _add_tool(spec, last, tip, tool_points, scale, effects.payload)
    _joint_dynamics(spec, chain, options.dynamics if options.inertia in ("auto", "own")
                    else None)
    _add_drives(spec, chain, load_friction)
    # the poses random measurements command (zrp.kinematics.sampling.default_limits), slides
    # from the model's length unit to m
    lim = default_limits(true_model) * np.where(true_model.prismatic, scale, 1.0)[:, None]
    g = _tune(spec, chain, effects, options, lim[:, 0], lim[:, 1])
    compiled = spec.compile()
    return compiled, _indices(compiled, chain, effects, len(tool_points), tip,
                              {"kp": g.kp, "kv": g.kv, "ki": g.ki})


def _indices(m: mujoco.MjModel, chain: _Chain, eff: HiddenEffects, points: int, tip: F64,
             gains: dict[str, F64]) -> dict[str, Any]:
    def jid(nm: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, nm)

    def bid(nm: str) -> int:
        return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, nm)

    ids: dict[str, Any] = {
        "motor_q": np.array([m.jnt_qposadr[jid(nm)] for nm in chain.motor]),
        "motor_v": np.array([m.jnt_dofadr[jid(nm)] for nm in chain.motor]),
        "play_q": np.array([-1 if nm is None else m.jnt_qposadr[jid(nm)]
                            for nm in chain.play]),
        "pos_bodies": np.array([bid(nm) for nm in chain.positioned]),
        "link_bodies": np.array([bid(nm) for nm in chain.links]),
        "payload": bid("payload") if eff.payload > 0 else -1,
        "sites": np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"smr{j + 1}")
                           for j in range(points)]),
        "tool_site": mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "tool"),
        **gains,
        "trim": np.array([(k + 1) not in eff.joint_compliance for k in range(len(chain.motor))]),
    }
    ids["body_pos0"] = m.body_pos[ids["pos_bodies"]].copy()
    ids["body_ipos0"] = m.body_ipos[ids["link_bodies"]].copy()
    ids["site_pos0"] = m.site_pos.copy()
    ids["tip_m"] = tip.copy()
    return ids
