"""Build a MuJoCo model (through :class:`mujoco.MjSpec`) from a ZRP manipulator model.

Layout (every body frame is aligned with the base frame at q = 0):

* body ``link{k}`` (k = 1..n) is a child of ``link{k-1}`` (the world for k = 1), at position
  b_{k,0} converted to metres, with one joint whose axis is u_{k,0} and whose anchor is the body
  origin (the point on joint k). qpos = 0 is the zero reference position, so MuJoCo's hinge
  angles are the ZRP joint values (rad) and slide values are the prismatic ones (in metres);
* site ``end_effector`` in ``link{n}`` at b_{n+1,0}, oriented by the hand frame
  ``zrp.hand_frame(u_a, u_t)`` = columns (u_t x u_a, u_t, u_a);
* visual geoms (no collisions): a capsule along each body vector b_k (in the body of joint k-1),
  a cylinder along each joint axis u_k, a small RGB triad at the end effector, optionally a floor
  and a pedestal under the base.

So MuJoCo's forward kinematics of this model is the ZRP product of exponentials exactly.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjcf.inertia import INERTIA_MODELS, BodyInertia, puma560_inertias, rod_inertias
from zrp.errors import InputError, OutputExistsError
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = [
    "BuiltArm",
    "MJCFOptions",
    "build",
    "build_spec",
    "mjcf_xml",
    "save_mjcf",
]

F64 = NDArray[np.float64]
RGBA = tuple[float, float, float, float]

LINK_RGBA: RGBA = (0.55, 0.62, 0.72, 1.0)
REVOLUTE_RGBA: RGBA = (0.95, 0.55, 0.15, 1.0)
PRISMATIC_RGBA: RGBA = (0.30, 0.75, 0.35, 1.0)
BASE_RGBA: RGBA = (0.35, 0.35, 0.38, 1.0)
FLOOR_RGBA: RGBA = (0.88, 0.88, 0.86, 1.0)
_NAME_OK = re.compile(r"^[A-Za-z_][A-Za-z0-9_.:-]*$")


def _check_rgba(value: ArrayLike, name: str) -> RGBA:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise InputError(f"{name}: expected 4 numbers in [0, 1] (r, g, b, a), got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]), float(arr[3]))


def _check_positive(value: float, name: str, unit: str, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {value!r}") from exc
    ok = v >= 0 if allow_zero else v > 0
    if not (math.isfinite(v) and ok):
        bound = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{name}: expected a finite number {bound} ({unit}), got {value!r}")
    return v


@dataclass(frozen=True)
class MJCFOptions:
    """How to build the MJCF model.

    Attributes:
        inertia: "none" (1 g placeholder bodies: kinematics only), "rods" (uniform rods and
            motor masses, any arm) or "puma560" (literature values, 6R PUMA-type arms only).
        actuators: add a PD servo per joint: a position actuator ``servo{k}`` (gain ``kp``) and,
            if ``kv > 0``, a velocity actuator ``servo{k}_rate`` (gain ``kv``). ctrl holds the
            n position set points, then the n rate set points (0 = plain damping).
        kp: position gain, N m/rad (N/m for prismatic joints).
        kv: velocity gain, N m s/rad (N s/m).
        gravity_compensation: compensate gravity on every body (MuJoCo ``gravcomp``).
        gravity: gravity vector, m/s^2, shape (3,).
        timestep: simulation step, s.
        visuals: add link capsules, joint cylinders and the end-effector triad.
        floor: add a floor and a pedestal under the base.
        alpha: opacity multiplier of every visual (e.g. 0.3 for a ghost arm).
        link_rgba: colour of the link capsules.
        tint: if given, one colour for every visual of the arm (e.g. a pale "ghost" arm).
        link_radius: capsule radius, m; None picks 2.2 % of the arm's reach.
        prefix: prefix of every element name (to put several arms in one scene).
        offscreen_size: (width, height) of MuJoCo's offscreen framebuffer, pixels.
    """

    inertia: str = "none"
    actuators: bool = False
    kp: float = 2000.0
    kv: float = 100.0
    gravity_compensation: bool = False
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    timestep: float = 1e-3
    visuals: bool = True
    floor: bool = True
    alpha: float = 1.0
    link_rgba: RGBA = LINK_RGBA
    tint: RGBA | None = None
    link_radius: float | None = None
    prefix: str = ""
    offscreen_size: tuple[int, int] = (1280, 960)

    def __post_init__(self) -> None:
        if self.inertia not in INERTIA_MODELS:
            raise InputError(f"inertia: unknown model {self.inertia!r}; expected one of "
                             f"{INERTIA_MODELS}")
        _check_positive(self.kp, "kp", "N m/rad")
        _check_positive(self.kv, "kv", "N m s/rad", allow_zero=True)
        _check_positive(self.timestep, "timestep", "s")
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputError(f"gravity: expected 3 finite numbers (m/s^2), got {self.gravity!r}")
        object.__setattr__(self, "gravity", tuple(float(x) for x in g))
        a = _check_positive(self.alpha, "alpha", "opacity in (0, 1]")
        if a > 1:
            raise InputError(f"alpha: expected an opacity in (0, 1], got {self.alpha!r}")
        object.__setattr__(self, "link_rgba", _check_rgba(self.link_rgba, "link_rgba"))
        if self.tint is not None:
            object.__setattr__(self, "tint", _check_rgba(self.tint, "tint"))
        if self.link_radius is not None:
            _check_positive(self.link_radius, "link_radius", "m")
        if self.prefix and not _NAME_OK.match(self.prefix):
            raise InputError(f"prefix: {self.prefix!r} is not a valid MJCF name prefix; use "
                             f"letters, digits and _ . : -")
        size = tuple(int(x) for x in self.offscreen_size)
        if len(size) != 2 or min(size) < 1:
            raise InputError(f"offscreen_size: expected (width, height) in pixels, got "
                             f"{self.offscreen_size!r}")
        object.__setattr__(self, "offscreen_size", size)


@dataclass(frozen=True, eq=False)
class BuiltArm:
    """A compiled MuJoCo model of a ZRP manipulator and the indices to drive and read it.

    Attributes:
        manipulator: the ZRP model it was built from.
        spec: the :class:`mujoco.MjSpec` (kept for XML export).
        model: the compiled :class:`mujoco.MjModel`.
        options: the build options.
        scale: metres per model length unit.
        qpos_adr: qpos address of joint k, shape (n,).
        dof_adr: dof address of joint k, shape (n,).
        site_id: id of the end-effector site.
        body_ids: ids of the bodies link1..linkn, shape (n,).
    """

    manipulator: Manipulator
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    options: MJCFOptions
    scale: float
    qpos_adr: NDArray[np.int64]
    dof_adr: NDArray[np.int64]
    site_id: int
    body_ids: NDArray[np.int64]
    _qscale: F64 = field(repr=False, default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        qscale = np.where(self.manipulator.prismatic, self.scale, 1.0)
        object.__setattr__(self, "_qscale", qscale)

    @property
    def site_name(self) -> str:
        return f"{self.options.prefix}end_effector"

    def qpos(self, q: ArrayLike) -> F64:
        """ZRP joint values (rad; model length unit for prismatic), shape (..., n), to MuJoCo
        joint values (rad; m), same shape."""
        return np.asarray(q, dtype=float) * self._qscale

    def q_from_qpos(self, qpos: ArrayLike) -> F64:
        """Inverse of :meth:`qpos`: MuJoCo values of the arm's joints, shape (..., n)."""
        return np.asarray(qpos, dtype=float) / self._qscale


def _hand_quat(model: Manipulator) -> F64:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(model.end_effector.frame).ravel())
    return quat


def _visual_geom(body: mujoco.MjsBody, kind: mujoco.mjtGeom, rgba: list[float], *,
                 size: ArrayLike, fromto: ArrayLike | None = None, pos: ArrayLike | None = None,
                 name: str = "", group: int = 0) -> mujoco.MjsGeom:
    geom = body.add_geom(type=kind, size=list(np.asarray(size, dtype=float)), rgba=rgba,
                         contype=0, conaffinity=0, group=group, density=0.0)
    if name:
        geom.name = name
    if fromto is not None:
        geom.fromto = list(np.asarray(fromto, dtype=float))
    if pos is not None:
        geom.pos = list(np.asarray(pos, dtype=float))
    return geom


def _inertias(model: Manipulator, options: MJCFOptions, scale: float) -> list[BodyInertia]:
    if options.inertia == "puma560":
        return puma560_inertias(model, scale)
    if options.inertia == "rods":
        return rod_inertias(model, scale)
    tiny = 1e-6 * np.eye(3)
    return [BodyInertia(mass=1e-3, com=np.zeros(3), inertia=tiny) for _ in range(model.n)]


def build_spec(model: Manipulator, options: MJCFOptions | None = None) -> mujoco.MjSpec:
    """The :class:`mujoco.MjSpec` of ``model`` (see the module docstring for the layout)."""
    if not isinstance(model, Manipulator):
        raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
    options = options or MJCFOptions()
    scale = metres_per_unit(model.length_unit, "model.length_unit")
    pre = options.prefix
    bodies_m = np.asarray(model.bodies) * scale
    axes = np.asarray(model.axes)
    reach_m = float(np.sum(np.linalg.norm(bodies_m, axis=1))) or 1.0
    radius = options.link_radius or 0.022 * reach_m

    spec = mujoco.MjSpec()
    spec.modelname = re.sub(r"[^A-Za-z0-9_.-]+", "_", model.name).strip("_") or "arm"
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    spec.option.timestep = options.timestep
    spec.option.gravity = list(options.gravity)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.visual.global_.offwidth = options.offscreen_size[0]
    spec.visual.global_.offheight = options.offscreen_size[1]
    spec.visual.quality.shadowsize = 2048
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.55, 0.55, 0.55]
    spec.stat.extent = 1.2 * reach_m
    spec.stat.center = [0.0, 0.0, 0.0]

    alpha = options.alpha
    tint = options.tint

    def colour(rgba: RGBA | list[float]) -> list[float]:
        base = tint if tint is not None else rgba
        return [base[0], base[1], base[2], base[3] * alpha]

    world = spec.worldbody
    if options.visuals and options.floor:
        floor_z = -reach_m
        light = world.add_light(name=f"{pre}light", pos=[0.0, -reach_m, 3 * reach_m],
                                dir=[0.0, 0.3, -1.0])
        light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        light.castshadow = False
        _visual_geom(world, mujoco.mjtGeom.mjGEOM_PLANE, colour(FLOOR_RGBA),
                     size=[2 * reach_m, 2 * reach_m, 0.05], pos=[0, 0, floor_z],
                     name=f"{pre}floor", group=2)
        _visual_geom(world, mujoco.mjtGeom.mjGEOM_CYLINDER, colour(BASE_RGBA),
                     size=[2.5 * radius, 0], fromto=[0, 0, floor_z, 0, 0, -2 * radius],
                     name=f"{pre}pedestal", group=2)
    if options.visuals:
        _visual_geom(world, mujoco.mjtGeom.mjGEOM_CYLINDER, colour(BASE_RGBA),
                     size=[2.5 * radius, 0], fromto=[0, 0, -2 * radius, 0, 0, 0],
                     name=f"{pre}base", group=1)

    inertias = _inertias(model, options, scale)
    joint_names: list[str] = []
    parent = world
    link_rgba = colour(options.link_rgba)
    for k in range(model.n):
        b = bodies_m[k]
        if options.visuals and np.linalg.norm(b) > 1e-9:
            _visual_geom(parent, mujoco.mjtGeom.mjGEOM_CAPSULE, link_rgba, size=[radius, 0, 0],
                         fromto=[0, 0, 0, *b], name=f"{pre}b{k + 1}")
        body = parent.add_body(name=f"{pre}link{k + 1}", pos=list(b))
        joint = body.add_joint(name=f"{pre}{_joint_name(model, k)}", axis=list(axes[k]))
        joint.type = (mujoco.mjtJoint.mjJNT_SLIDE if model.prismatic[k]
                      else mujoco.mjtJoint.mjJNT_HINGE)
        joint.armature = inertias[k].armature
        inert = inertias[k]
        body.explicitinertial = True
        body.mass = inert.mass
        body.ipos = list(inert.com)
        body.fullinertia = inert.fullinertia
        if options.gravity_compensation:
            body.gravcomp = 1.0
        if options.visuals:
            u = axes[k]
            if model.prismatic[k]:
                _visual_geom(body, mujoco.mjtGeom.mjGEOM_BOX, colour(PRISMATIC_RGBA),
                             size=[1.1 * radius] * 3, name=f"{pre}u{k + 1}")
            else:
                h = 1.6 * radius
                _visual_geom(body, mujoco.mjtGeom.mjGEOM_CYLINDER,
                             colour(REVOLUTE_RGBA), size=[1.35 * radius, 0],
                             fromto=[*(-h * u), *(h * u)], name=f"{pre}u{k + 1}")
        joint_names.append(joint.name)
        parent = body

    if options.actuators:
        # PD servo per joint as two actuators: position (kp), then rate (kv) set points, so
        # ctrl = [n positions, n rates]. With rate set points 0 this is MuJoCo's position
        # actuator with damping kv; feeding the reference rates removes the kv * qdot lag.
        for k, jname in enumerate(joint_names):
            act = spec.add_actuator(name=f"{pre}servo{k + 1}", target=jname,
                                    trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_position(kp=options.kp, kv=0.0)
        if options.kv > 0:
            for k, jname in enumerate(joint_names):
                vel = spec.add_actuator(name=f"{pre}servo{k + 1}_rate", target=jname,
                                        trntype=mujoco.mjtTrn.mjTRN_JOINT)
                vel.set_to_velocity(kv=options.kv)

    tip = bodies_m[model.n]
    if options.visuals and np.linalg.norm(tip) > 1e-9:
        _visual_geom(parent, mujoco.mjtGeom.mjGEOM_CAPSULE, link_rgba,
                     size=[0.6 * radius, 0, 0], fromto=[0, 0, 0, *tip],
                     name=f"{pre}b{model.n + 1}")
    parent.add_site(name=f"{pre}end_effector", pos=list(tip), quat=list(_hand_quat(model)),
                    size=[0.5 * radius, 0, 0], rgba=[1.0, 1.0, 1.0, 0.0])
    if options.visuals:
        frame = model.end_effector.frame
        colours = ([0.9, 0.15, 0.15], [0.15, 0.8, 0.15], [0.15, 0.3, 0.95])
        for col, name in enumerate("xyz"):
            d = frame[:, col] * 3.0 * radius
            _visual_geom(parent, mujoco.mjtGeom.mjGEOM_CAPSULE, colour([*colours[col], 1.0]),
                         size=[0.25 * radius, 0, 0], fromto=[*tip, *(tip + d)],
                         name=f"{pre}hand_{name}", group=1)
    return spec


def _joint_name(model: Manipulator, k: int) -> str:
    name = model.joint_names[k]
    return name if _NAME_OK.match(name) else f"q{k + 1}"


def build(model: Manipulator, options: MJCFOptions | None = None) -> BuiltArm:
    """Build and compile the MuJoCo model of ``model``.

    Raises:
        InputError: bad options (the message names the option).
        mjcf.MJCFCompileError: MuJoCo refused the model (its message is included).
    """
    from mjcf.errors import MJCFCompileError

    options = options or MJCFOptions()
    spec = build_spec(model, options)
    try:
        compiled = spec.compile()
    except ValueError as exc:  # MuJoCo's compiler errors
        raise MJCFCompileError(f"MuJoCo could not compile the model of {model.name!r}: "
                               f"{exc}") from exc
    pre = options.prefix
    jids = [mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, f"{pre}{_joint_name(model, k)}")
            for k in range(model.n)]
    bids = [mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_BODY, f"{pre}link{k + 1}")
            for k in range(model.n)]
    site = mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_SITE, f"{pre}end_effector")
    return BuiltArm(
        manipulator=model,
        spec=spec,
        model=compiled,
        options=options,
        scale=metres_per_unit(model.length_unit, "model.length_unit"),
        qpos_adr=np.array([compiled.jnt_qposadr[j] for j in jids], dtype=np.int64),
        dof_adr=np.array([compiled.jnt_dofadr[j] for j in jids], dtype=np.int64),
        site_id=int(site),
        body_ids=np.array(bids, dtype=np.int64),
    )


def _fmt(values: ArrayLike) -> str:
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def mjcf_xml(arm: BuiltArm | Manipulator, options: MJCFOptions | None = None) -> str:
    """MJCF text of a built arm (or of a model, built with ``options``).

    MuJoCo's writer keeps 6 significant digits; the kinematic attributes (body positions,
    joint axes, the end-effector site) are rewritten here at full double precision so that the
    file reproduces the model exactly.
    """
    if isinstance(arm, Manipulator):
        arm = build(arm, options)
    elif not isinstance(arm, BuiltArm):
        raise InputError(f"arm: expected a mjcf.BuiltArm or a zrp.Manipulator, got "
                         f"{type(arm).__name__}")
    text = arm.spec.to_xml()
    root = ET.fromstring(text)
    model = arm.manipulator
    pre = arm.options.prefix
    bodies_m = np.asarray(model.bodies) * arm.scale
    by_name = {el.get("name"): el for el in root.iter() if el.get("name")}
    for k in range(model.n):
        body = by_name[f"{pre}link{k + 1}"]
        body.set("pos", _fmt(bodies_m[k]))
        joint = by_name[f"{pre}{_joint_name(model, k)}"]
        joint.set("axis", _fmt(model.axes[k]))
    site = by_name[f"{pre}end_effector"]
    site.set("pos", _fmt(bodies_m[model.n]))
    site.set("quat", _fmt(_hand_quat(model)))
    ET.indent(root, space="  ")
    comment = (f"<!-- {model.name}: built by zrp-accuracy mjcf from a zero-reference-position "
               f"model ({model.length_unit} -> m x {arm.scale:g}); qpos = 0 is the zero "
               f"reference. -->\n")
    return comment + ET.tostring(root, encoding="unicode") + "\n"


def save_mjcf(arm: BuiltArm | Manipulator, path: str | Path, *, overwrite: bool = False,
              options: MJCFOptions | None = None) -> Path:
    """Write :func:`mjcf_xml` to ``path``; refuses to replace a file unless ``overwrite``."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputExistsError(f"output {str(path)!r} exists; pass overwrite=True (--force) to "
                                f"replace it")
    if path.is_dir():
        raise InputError(f"output {str(path)!r} is a directory; expected a .xml file path")
    text = mjcf_xml(arm, options)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        from mjcf.errors import MJCFOutputError

        raise MJCFOutputError(f"output {str(path)!r}: cannot write ({exc.strerror or exc})") \
            from exc
    return path
