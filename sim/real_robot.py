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

Link inertias: the PUMA 560 literature values (:func:`mjcf.puma560_inertias`, Armstrong,
Khatib & Burdick 1986 via Corke & Armstrong-Hélouvry 1994) for 6R PUMA-type models, uniform
rods otherwise (:func:`mjcf.rod_inertias`). Layout as in :mod:`mjcf.builder`: body frames are
world-aligned at q = 0, body k sits at b_{k,0} (metres), joint k turns about u_{k,0}.

Units: joint values rad (model length unit for prismatic joints), positions in the model's
length unit in the API (MuJoCo works in metres inside), torques N m, masses kg, deg C.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjcf.inertia import BodyInertia, puma560_inertias, rod_inertias
from zrp.errors import InputError
from zrp.gap.effects import EFFECTS as GAP_EFFECTS
from zrp.manufacturing.sensitivity import axis_tangents, tilt_axes
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = [
    "EFFECT_NAMES",
    "PUMA560_LOAD_FRICTION",
    "HiddenEffects",
    "Reading",
    "RealRobot",
    "RealRobotOptions",
    "Session",
    "default_tool_points",
    "motor_map",
    "true_geometry",
]

F64 = NDArray[np.float64]

#: Effects the real robot can hide: exactly the diagnosis's candidates (one list for both).
EFFECT_NAMES: tuple[str, ...] = GAP_EFFECTS

#: Coulomb friction of the load side of each PUMA 560 joint against its parent, N m: 20 % of
#: the drive's total Coulomb friction, i.e. of the motor-side values of Armstrong et al.
#: (1986) as tabulated by Corke & Armstrong-Hélouvry (1994) (0.395, 0.126, 0.132, 0.0112,
#: 0.00926, 0.00396 N m) times the gear ratios (62.6, 107.8, 53.7, 76.0, 71.9, 76.7). The
#: 20 % (bearing and output-stage share, our assumption) only matters inside the backlash: it
#: holds the load where the last slow approach left it unless gravity is stronger.
PUMA560_LOAD_FRICTION = (4.94, 2.72, 1.42, 0.170, 0.133, 0.0607)


def _freeze(a: ArrayLike) -> F64:
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


def _finite(v: object, where: str, unit: str) -> float:
    try:
        x = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: expected a number ({unit}), got {v!r}") from exc
    if not math.isfinite(x):
        raise InputError(f"{where}: expected a finite number ({unit}), got {v!r}")
    return x


def _joint_map(value: Mapping[int, Any] | None, name: str, conv: Any) -> Mapping[int, Any]:
    if value is None:
        return MappingProxyType({})
    if not isinstance(value, Mapping):
        raise InputError(f"{name}: expected a mapping from 1-based joint number to a value, got "
                         f"{type(value).__name__}")
    out: dict[int, Any] = {}
    for k, v in value.items():
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or int(k) < 1:
            raise InputError(f"{name}: key {k!r} is not a 1-based joint number")
        out[int(k)] = conv(v, f"{name}[{int(k)}]")
    return MappingProxyType(dict(sorted(out.items())))


def _vec(n: int, unit: str) -> Any:
    def conv(v: object, where: str) -> tuple[float, ...]:
        arr = np.asarray(v, dtype=float).ravel()
        if arr.shape != (n,) or not np.all(np.isfinite(arr)):
            raise InputError(f"{where}: expected {n} finite numbers ({unit}), got {v!r}")
        return tuple(float(x) for x in arr)
    return conv


def _positive(unit: str) -> Any:
    def conv(v: object, where: str) -> float:
        x = _finite(v, where, unit)
        if x <= 0:
            raise InputError(f"{where}: expected a value > 0 ({unit}), got {v!r}")
        return x
    return conv


def _cyclic(v: object, where: str) -> tuple[int, float, float]:
    try:
        h, a, b = v  # type: ignore[misc]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: expected (harmonic h >= 1, sin amplitude rad, cos amplitude "
                         f"rad), got {v!r}") from exc
    if isinstance(h, bool) or int(h) != h or int(h) < 1:
        raise InputError(f"{where}: harmonic {h!r} must be an integer >= 1")
    return (int(h), _finite(a, where, "rad"), _finite(b, where, "rad"))


@dataclass(frozen=True)
class HiddenEffects:
    """Effects of the real robot that the nominal model does not know (all off by default).

    Joint keys are 1-based. Attributes:
        joint_offset: encoder zero error per joint, rad (model length unit if prismatic); the
            true motor angle is q + offset.
        encoder_scale: scale error per joint (dimensionless): true = q (1 + s).
        cyclic_error: per joint (h, a, b): true += a sin(h q) + b cos(h q), a and b in rad.
        link_length: body-vector error db_k (model length unit, zero-reference base frame) per
            body k = 1..n+1 (n+1: the end effector's).
        axis_misalignment: per joint, tilt (a, b) in rad of the axis towards its tangents t1,
            t2 (:func:`zrp.manufacturing.axis_tangents`), applied exactly (rotation by |w|).
        joint_compliance: per joint, rad/(N m): the servo stiffness is 1/c and has no integral
            action, so the joint deflects by -c tau under the static torque tau it carries.
        backlash: per joint, the total free play b between motor and load, rad; the load lags
            by b/2 behind a slow approach (unless gravity holds it on the other flank).
        thermal_expansion: alpha, 1/K: body vectors scale by 1 + alpha (T - t_ref).
        payload: kg, a point mass at the end-effector point (0: none).
    """

    joint_offset: Mapping[int, float] = field(default_factory=dict)
    encoder_scale: Mapping[int, float] = field(default_factory=dict)
    cyclic_error: Mapping[int, tuple[int, float, float]] = field(default_factory=dict)
    link_length: Mapping[int, tuple[float, float, float]] = field(default_factory=dict)
    axis_misalignment: Mapping[int, tuple[float, float]] = field(default_factory=dict)
    joint_compliance: Mapping[int, float] = field(default_factory=dict)
    backlash: Mapping[int, float] = field(default_factory=dict)
    thermal_expansion: float = 0.0
    payload: float = 0.0

    def __post_init__(self) -> None:
        fin = (lambda v, w: _finite(v, w, "see HiddenEffects"))  # noqa: E731
        object.__setattr__(self, "joint_offset", _joint_map(self.joint_offset, "joint_offset",
                                                            fin))
        object.__setattr__(self, "encoder_scale", _joint_map(self.encoder_scale,
                                                             "encoder_scale", fin))
        object.__setattr__(self, "cyclic_error", _joint_map(self.cyclic_error, "cyclic_error",
                                                            _cyclic))
        object.__setattr__(self, "link_length", _joint_map(self.link_length, "link_length",
                                                           _vec(3, "length unit")))
        object.__setattr__(self, "axis_misalignment", _joint_map(
            self.axis_misalignment, "axis_misalignment", _vec(2, "rad")))
        object.__setattr__(self, "joint_compliance", _joint_map(
            self.joint_compliance, "joint_compliance", _positive("rad/(N m)")))
        object.__setattr__(self, "backlash", _joint_map(self.backlash, "backlash",
                                                        _positive("rad")))
        a = _finite(self.thermal_expansion, "thermal_expansion", "1/K")
        if abs(a) > 1e-3:
            raise InputError(f"thermal_expansion: {a!r} 1/K is implausible; expected a linear "
                             "expansion coefficient such as 1.2e-5 (steel) or 2.3e-5 (aluminium)")
        object.__setattr__(self, "thermal_expansion", a)
        m = _finite(self.payload, "payload", "kg")
        if m < 0:
            raise InputError(f"payload: expected a mass >= 0 kg, got {self.payload!r}")
        object.__setattr__(self, "payload", m)
        for k, s in self.encoder_scale.items():
            if abs(s) >= 0.1:
                raise InputError(f"encoder_scale[{k}]: {s!r} is not a small scale error; "
                                 "expected |s| < 0.1")

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        # the mappings are read-only proxies, which do not pickle: go through the plain form
        return (HiddenEffects.from_dict, (self.to_dict(),))

    @property
    def active(self) -> tuple[str, ...]:
        """Names of the effects switched on (in :data:`EFFECT_NAMES` order)."""
        out = []
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            on = bool(v) if isinstance(v, Mapping) else v != 0.0
            if isinstance(v, Mapping) and name in ("joint_offset", "encoder_scale"):
                on = any(x != 0.0 for x in v.values())
            if on:
                out.append(name)
        return tuple(out)

    def joints(self, effect: str) -> tuple[int, ...]:
        """Joints (bodies for ``link_length``) an effect is switched on for; () if global."""
        if effect not in EFFECT_NAMES:
            raise InputError(f"effect: {effect!r} is not one of {EFFECT_NAMES}")
        v = getattr(self, effect)
        return tuple(sorted(v)) if isinstance(v, Mapping) else ()

    def check(self, model: Manipulator) -> None:
        """Raise :class:`InputError` if a joint or body number does not exist in ``model``."""
        n = model.n
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            if not isinstance(v, Mapping):
                continue
            top = n + 1 if name == "link_length" else n
            bad = [k for k in v if k > top]
            if bad:
                what = "bodies 1.." if name == "link_length" else "joints 1.."
                raise InputError(f"{name}: {bad} out of range; the model {model.name!r} has "
                                 f"{what}{top}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (keys as strings); inverse of :meth:`from_dict`."""
        out: dict[str, Any] = {}
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            out[name] = ({str(k): (list(x) if isinstance(x, tuple) else x) for k, x in v.items()}
                         if isinstance(v, Mapping) else v)
        out["payload"] = self.payload
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HiddenEffects:
        """Build from :meth:`to_dict` output."""
        unknown = set(data) - {*EFFECT_NAMES, "payload"}
        if unknown:
            raise InputError(f"hidden effects: unknown key(s) {sorted(unknown)}; expected "
                             f"{[*EFFECT_NAMES, 'payload']}")
        kw: dict[str, Any] = {}
        for name, v in data.items():
            if isinstance(v, Mapping):
                kw[name] = {int(k): (tuple(x) if isinstance(x, list) else x)
                            for k, x in v.items()}
            else:
                kw[name] = v
        return cls(**kw)


def motor_map(effects: HiddenEffects, q: ArrayLike) -> F64:
    """True motor angles for controller joint values ``q`` (rad), shape (..., n) -> same:
    q + offset + s q + a sin(h q) + b cos(h q) (the encoder/transmission effects)."""
    q = np.asarray(q, dtype=float)
    out = q.copy()
    for k, v in effects.joint_offset.items():
        out[..., k - 1] += v
    for k, s in effects.encoder_scale.items():
        out[..., k - 1] += s * q[..., k - 1]
    for k, (h, a, b) in effects.cyclic_error.items():
        out[..., k - 1] += a * np.sin(h * q[..., k - 1]) + b * np.cos(h * q[..., k - 1])
    return out


def true_geometry(model: Manipulator, effects: HiddenEffects) -> Manipulator:
    """The real robot's geometry at t_ref: body vectors + link_length errors, axes tilted
    exactly by axis_misalignment (:func:`zrp.manufacturing.sensitivity.tilt_axes`)."""
    bodies = np.array(model.bodies, dtype=float)
    for k, db in effects.link_length.items():
        bodies[k - 1] += np.asarray(db)
    tilts = np.zeros((model.n, 2))
    for k, ab in effects.axis_misalignment.items():
        tilts[k - 1] = ab
    axes = tilt_axes(model.axes, axis_tangents(model.axes), tilts)
    return model.with_arrays(axes=axes, bodies=bodies, name=f"{model.name} (real)")


def default_tool_points(model: Manipulator) -> F64:
    """Three reflector positions on the tool relative to the end-effector point, in the
    zero-reference base frame, model length unit, shape (3, 3): a triangle of about 6 % of
    the reach (50-70 mm on the PUMA)."""
    base = np.array([[50.0, 0.0, 30.0], [-40.0, 60.0, 30.0], [0.0, -70.0, 40.0]])
    return _freeze(base * model.reach / 1244.6)


@dataclass(frozen=True)
class RealRobotOptions:
    """How the real robot is built and driven.

    Attributes:
        inertia: "auto" (PUMA 560 values for a 6R arm, rods otherwise), "puma560" or "rods".
        servo_kp: stiffness of the servos of joints without compliance, N m/rad (N/m); their
            integral action removes the steady-state error whatever it is.
        damping_ratio: servo damping ratio (kv from kp and the joint's inertia at q = 0).
        load_friction: Coulomb friction of each load-side hinge (backlash joints only), N m,
            shape (n,); None: :data:`PUMA560_LOAD_FRICTION` for the PUMA, 1 N m otherwise.
        tool_points: reflector offsets from the end-effector point, zero-reference base frame,
            model length unit, shape (M, 3); None: :func:`default_tool_points`.
        t_ref: temperature at which the geometry is the model's, deg C.
        gravity: m/s^2, shape (3,).
        timestep: s; None picks <= 1 ms from the stiffest servo.
    """

    inertia: str = "auto"
    servo_kp: float = 2.0e4
    damping_ratio: float = 1.0
    load_friction: tuple[float, ...] | None = None
    tool_points: tuple[tuple[float, float, float], ...] | None = None
    t_ref: float = 20.0
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    timestep: float | None = None

    def __post_init__(self) -> None:
        if self.inertia not in ("auto", "puma560", "rods"):
            raise InputError(f"inertia: {self.inertia!r}; expected 'auto', 'puma560' or 'rods'")
        for name, unit in (("servo_kp", "N m/rad"), ("damping_ratio", "1")):
            v = _finite(getattr(self, name), name, unit)
            if v <= 0:
                raise InputError(f"{name}: expected a value > 0 ({unit}), got {v!r}")
            object.__setattr__(self, name, v)
        if self.load_friction is not None:
            f = np.asarray(self.load_friction, dtype=float).ravel()
            if not np.all(np.isfinite(f)) or np.any(f < 0):
                raise InputError(f"load_friction: expected finite values >= 0 (N m), got "
                                 f"{self.load_friction!r}")
            object.__setattr__(self, "load_friction", tuple(float(x) for x in f))
        if self.tool_points is not None:
            t = np.asarray(self.tool_points, dtype=float)
            if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] < 1 or not np.all(np.isfinite(t)):
                raise InputError(f"tool_points: expected shape (M, 3) of finite numbers (model "
                                 f"length unit), got {np.shape(self.tool_points)}")
            object.__setattr__(self, "tool_points", tuple(tuple(float(x) for x in r) for r in t))
        _finite(self.t_ref, "t_ref", "deg C")
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputError(f"gravity: expected 3 finite numbers (m/s^2), got {self.gravity!r}")
        object.__setattr__(self, "gravity", tuple(float(x) for x in g))
        if self.timestep is not None:
            dt = _finite(self.timestep, "timestep", "s")
            if not 0 < dt <= 0.01:
                raise InputError(f"timestep: expected 0 < dt <= 0.01 s, got {self.timestep!r}")


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

    Use :meth:`session` to drive it (the measuring procedure in :mod:`sim.measurement` does).
    """

    def __init__(self, model: Manipulator, effects: HiddenEffects | None = None,
                 options: RealRobotOptions | None = None) -> None:
        if not isinstance(model, Manipulator):
            raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
        self.nominal = model
        self.effects = effects or HiddenEffects()
        if not isinstance(self.effects, HiddenEffects):
            raise InputError(f"effects: expected sim.real_robot.HiddenEffects, got "
                             f"{type(self.effects).__name__}")
        self.effects.check(model)
        self.options = options or RealRobotOptions()
        n = model.n
        self.n = n
        self.scale = metres_per_unit(model.length_unit, "model.length_unit")
        self.true_model = self._true_geometry()
        tp = (default_tool_points(model) if self.options.tool_points is None
              else np.asarray(self.options.tool_points, dtype=float))
        self.tool_points = _freeze(tp)
        fr = self.options.load_friction
        if fr is None:
            fr = PUMA560_LOAD_FRICTION if self._inertia_kind() == "puma560" else (1.0,) * n
        if len(fr) != n:
            raise InputError(f"load_friction: expected {n} values (one per joint), got {len(fr)}")
        self.load_friction = _freeze(fr)
        self.model, self._ids = self._build()

    # ---- construction ---------------------------------------------------------------------
    def _inertia_kind(self) -> str:
        kind = self.options.inertia
        if kind == "auto":
            m = self.nominal
            kind = "puma560" if m.n == 6 and not m.prismatic.any() else "rods"
        return kind

    def _true_geometry(self) -> Manipulator:
        return true_geometry(self.nominal, self.effects)

    def _inertias(self) -> list[BodyInertia]:
        if self._inertia_kind() == "puma560":
            return puma560_inertias(self.true_model, self.scale)
        return rod_inertias(self.true_model, self.scale)

    def _build(self) -> tuple[mujoco.MjModel, dict[str, Any]]:
        tm = self.true_model
        n = self.n
        eff = self.effects
        sc = self.scale
        bodies_m = np.asarray(tm.bodies) * sc
        axes = np.asarray(tm.axes)
        spec = mujoco.MjSpec()
        spec.modelname = "real_robot"
        spec.compiler.degree = False
        spec.compiler.autolimits = True
        spec.option.gravity = list(self.options.gravity)
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        inert = self._inertias()
        parent = spec.worldbody
        motor_names: list[str] = []
        play_names: list[str | None] = []
        link_names: list[str] = []
        pos_bodies: list[str] = []
        for k in range(n):
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
                half = 0.5 * eff.backlash[k + 1] * (sc if tm.prismatic[k] else 1.0)
                pj = body.add_joint(name=f"play{k + 1}", axis=ax, type=kind)
                pj.range = [-half, half]
                pj.armature = 1e-4
                motor_names.append(f"motor{k + 1}")
                play_names.append(f"play{k + 1}")
                pos_bodies.append(f"motor{k + 1}")
            else:
                body = parent.add_body(name=f"link{k + 1}", pos=list(bodies_m[k]))
                j = body.add_joint(name=f"q{k + 1}", axis=ax, type=kind)
                j.armature = max(inert[k].armature, 1e-3)
                motor_names.append(f"q{k + 1}")
                play_names.append(None)
                pos_bodies.append(f"link{k + 1}")
            body.explicitinertial = True
            body.mass = inert[k].mass
            body.ipos = list(inert[k].com)
            body.fullinertia = inert[k].fullinertia
            link_names.append(f"link{k + 1}")
            parent = body
        tip = bodies_m[n]
        parent.add_site(name="tool", pos=list(tip))
        for j, t in enumerate(self.tool_points):
            parent.add_site(name=f"smr{j + 1}", pos=list(tip + np.asarray(t) * sc))
        if eff.payload > 0:
            pl = parent.add_body(name="payload", pos=list(tip))
            pl.explicitinertial = True
            pl.mass = eff.payload
            pl.ipos = [0.0, 0.0, 0.0]
            r = 0.03
            i0 = 0.4 * eff.payload * r * r
            pl.fullinertia = [i0, i0, i0, 0.0, 0.0, 0.0]
        for k, name in enumerate(play_names):
            if name is None:
                continue
            ten = spec.add_tendon(name=f"bearing{k + 1}")
            ten.frictionloss = float(self.load_friction[k])
            ten.wrap_joint(motor_names[k], 1.0)
            ten.wrap_joint(name, 1.0)
        kps = np.full(n, self.options.servo_kp)
        for k, c in eff.joint_compliance.items():
            kps[k - 1] = 1.0 / c
        for k in range(n):
            act = spec.add_actuator(name=f"servo{k + 1}", target=motor_names[k],
                                    trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_position(kp=float(kps[k]), kv=0.0)
        for k in range(n):
            act = spec.add_actuator(name=f"servo{k + 1}_rate", target=motor_names[k],
                                    trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_velocity(kv=1.0)  # gain set below, once the inertias are known
        # inertia seen by each servo at q = 0 (for the damping and the time step)
        probe = spec.compile()
        d = mujoco.MjData(probe)
        mujoco.mj_forward(probe, d)
        full = np.zeros((probe.nv, probe.nv))
        mujoco.mj_fullM(probe, d, full)
        mdof = [probe.jnt_dofadr[mujoco.mj_name2id(probe, mujoco.mjtObj.mjOBJ_JOINT, nm)]
                for nm in motor_names]
        inertia = np.array([full[i, i] for i in mdof])
        kvs = 2.0 * self.options.damping_ratio * np.sqrt(kps * inertia)
        dt = self.options.timestep
        if dt is None:
            dt = float(min(1e-3, 0.4 * np.min(np.sqrt(inertia / kps))))
        spec.option.timestep = dt
        for k, name in enumerate(play_names):
            if name is not None:
                pj = spec.joint(name)
                pj.solref_limit = [2.0 * dt, 1.0]
                pj.solimp_limit = [0.9999, 0.9999, 0.001, 0.5, 2.0]
                ten = spec.tendon(f"bearing{k + 1}")
                ten.solref_friction = [2.0 * dt, 1.0]
                ten.solimp_friction = [0.99999, 0.99999, 0.001, 0.5, 2.0]
        for k in range(n):
            spec.actuator(f"servo{k + 1}_rate").set_to_velocity(kv=float(kvs[k]))
        compiled = spec.compile()
        jid = (lambda nm: mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, nm))  # noqa: E731
        bid = (lambda nm: mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_BODY, nm))  # noqa: E731
        ids: dict[str, Any] = {
            "motor_q": np.array([compiled.jnt_qposadr[jid(nm)] for nm in motor_names]),
            "motor_v": np.array([compiled.jnt_dofadr[jid(nm)] for nm in motor_names]),
            "play_q": np.array([-1 if nm is None else compiled.jnt_qposadr[jid(nm)]
                                for nm in play_names]),
            "pos_bodies": np.array([bid(nm) for nm in pos_bodies]),
            "link_bodies": np.array([bid(nm) for nm in link_names]),
            "payload": bid("payload") if eff.payload > 0 else -1,
            "sites": np.array([mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_SITE, f"smr{j + 1}")
                               for j in range(len(self.tool_points))]),
            "tool_site": mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_SITE, "tool"),
            "kp": kps,
            "kv": kvs,
            "ki": 0.15 * np.sqrt(kps / inertia),
            "trim": np.array([(k + 1) not in eff.joint_compliance for k in range(n)]),
        }
        ids["body_pos0"] = compiled.body_pos[ids["pos_bodies"]].copy()
        ids["body_ipos0"] = compiled.body_ipos[ids["link_bodies"]].copy()
        ids["site_pos0"] = compiled.site_pos.copy()
        ids["tip_m"] = tip.copy()
        return compiled, ids

    # ---- the controller's view ------------------------------------------------------------
    @property
    def timestep(self) -> float:
        """Simulation step, s."""
        return float(self.model.opt.timestep)

    @property
    def servo_stiffness(self) -> F64:
        """kp per joint, N m/rad, shape (n,)."""
        return _freeze(self._ids["kp"])

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
        from zrp.kinematics.forward import forward_kinematics

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
        """The build (servo gains, time step, friction, inertias) for the truth file."""
        return {"timestep_s": self.timestep, "servo_kp_Nm_per_rad": self._ids["kp"].tolist(),
                "servo_kv_Nms_per_rad": self._ids["kv"].tolist(),
                "integral_trim": self._ids["trim"].tolist(),
                "load_friction_Nm": self.load_friction.tolist(),
                "inertia": self._inertia_kind(), "t_ref_degC": self.options.t_ref,
                "tool_points": self.tool_points.tolist(),
                "true_axes": np.asarray(self.true_model.axes).tolist(),
                "true_bodies": np.asarray(self.true_model.bodies).tolist(),
                "gravity_m_s2": list(self.options.gravity)}


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
        t = _finite(temperature, "temperature", "deg C")
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
        dur = _finite(duration, "duration", "s")
        if dur <= 0:
            raise InputError(f"duration: expected a time > 0 s, got {duration!r}")
        r = self.robot
        target = r.motor_target(np.asarray(q_to, dtype=float)) * self._q_scale
        start = self.ref.copy()
        delta = target - start
        periods = max(1, math.ceil(dur / self.period))
        T = periods * self.period
        for i in range(1, periods + 1):
            s = i / periods
            self.ref = start + (s**3 * (10 - 15 * s + 6 * s * s)) * delta
            self.rate = (30 * s * s * (1 - s) ** 2 / T) * delta
            self._apply()
            self._period()
        self.ref = target
        self.rate = np.zeros(self.n)
        self._apply()

    def settle(self, max_time: float = 2.0, check_every: float = 0.04, tol_rad: float = 1e-7,
               speed_tol: float = 1e-5) -> float:
        """Hold the references until the motors with integral action are within ``tol_rad``
        of their targets and no joint moves faster than ``speed_tol`` (rad/s), or
        ``max_time`` s passed. Returns the final largest joint speed (rad/s)."""
        every = max(1, round(check_every / self.period))
        mask = self.ids["trim"]
        speed = math.inf
        elapsed = 0.0
        while elapsed < max_time:
            for _ in range(every):
                err = self._period()
                self._apply()
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
        return Reading(points=_freeze(pts), q_link=_freeze(link), q_motor=_freeze(motor),
                       motor_target=_freeze(self.ref / self._q_scale),
                       torque=_freeze(torque), temperature=self.temperature,
                       residual_speed=float(residual_speed))
