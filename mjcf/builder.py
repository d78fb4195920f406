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
The XML text and file: :mod:`mjcf.writer`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjcf.errors import MJCFCompileError
from mjcf.inertia import BodyInertia, puma560_inertias, rod_inertias
from mjcf.options import (
    BASE_RGBA,
    FLOOR_RGBA,
    NAME_OK,
    PRISMATIC_RGBA,
    REVOLUTE_RGBA,
    RGBA,
    MJCFOptions,
)
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = [
    "BuiltArm",
    "build",
    "build_spec",
    "hand_quat",
    "joint_name",
]


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


def hand_quat(model: Manipulator) -> F64:
    """Quaternion (w, x, y, z) of the hand frame, the end-effector site's orientation."""
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


def _colour(rgba: RGBA | list[float], options: MJCFOptions) -> list[float]:
    """``rgba`` (or the tint) with the options' opacity applied."""
    base = options.tint if options.tint is not None else rgba
    return [base[0], base[1], base[2], base[3] * options.alpha]


def _new_spec(model: Manipulator, options: MJCFOptions, reach_m: float) -> mujoco.MjSpec:
    """An empty spec with the compiler, physics and visual settings."""
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
    return spec


def _add_surroundings(world: mujoco.MjsBody, options: MJCFOptions, reach_m: float,
                      radius: float) -> None:
    """Light, floor and pedestal (with ``floor``), and the base cylinder (with ``visuals``)."""
    if not options.visuals:
        return
    pre = options.prefix
    if options.floor:
        floor_z = -reach_m
        light = world.add_light(name=f"{pre}light", pos=[0.0, -reach_m, 3 * reach_m],
                                dir=[0.0, 0.3, -1.0])
        light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        light.castshadow = False
        _visual_geom(world, mujoco.mjtGeom.mjGEOM_PLANE, _colour(FLOOR_RGBA, options),
                     size=[2 * reach_m, 2 * reach_m, 0.05], pos=[0, 0, floor_z],
                     name=f"{pre}floor", group=2)
        _visual_geom(world, mujoco.mjtGeom.mjGEOM_CYLINDER, _colour(BASE_RGBA, options),
                     size=[2.5 * radius, 0], fromto=[0, 0, floor_z, 0, 0, -2 * radius],
                     name=f"{pre}pedestal", group=2)
    _visual_geom(world, mujoco.mjtGeom.mjGEOM_CYLINDER, _colour(BASE_RGBA, options),
                 size=[2.5 * radius, 0], fromto=[0, 0, -2 * radius, 0, 0, 0],
                 name=f"{pre}base", group=1)


def _add_joint_visual(body: mujoco.MjsBody, model: Manipulator, k: int, u: F64,
                      options: MJCFOptions, radius: float) -> None:
    """A box (prismatic) or a cylinder along the axis (revolute) marking joint k."""
    name = f"{options.prefix}u{k + 1}"
    if model.prismatic[k]:
        _visual_geom(body, mujoco.mjtGeom.mjGEOM_BOX, _colour(PRISMATIC_RGBA, options),
                     size=[1.1 * radius] * 3, name=name)
    else:
        h = 1.6 * radius
        _visual_geom(body, mujoco.mjtGeom.mjGEOM_CYLINDER, _colour(REVOLUTE_RGBA, options),
                     size=[1.35 * radius, 0], fromto=[*(-h * u), *(h * u)], name=name)


def _add_links(world: mujoco.MjsBody, model: Manipulator, options: MJCFOptions,
               scale: float, radius: float) -> tuple[list[str], mujoco.MjsBody]:
    """Bodies link1..linkn with their joints, mass properties and visuals.

    Returns:
        the joint names and the last body.
    """
    pre = options.prefix
    bodies_m = np.asarray(model.bodies) * scale
    axes = np.asarray(model.axes)
    inertias = _inertias(model, options, scale)
    link_rgba = _colour(options.link_rgba, options)
    joint_names: list[str] = []
    parent = world
    for k in range(model.n):
        b = bodies_m[k]
        if options.visuals and np.linalg.norm(b) > 1e-9:
            _visual_geom(parent, mujoco.mjtGeom.mjGEOM_CAPSULE, link_rgba, size=[radius, 0, 0],
                         fromto=[0, 0, 0, *b], name=f"{pre}b{k + 1}")
        body = parent.add_body(name=f"{pre}link{k + 1}", pos=list(b))
        joint = body.add_joint(name=f"{pre}{joint_name(model, k)}", axis=list(axes[k]))
        joint.type = (mujoco.mjtJoint.mjJNT_SLIDE if model.prismatic[k]
                      else mujoco.mjtJoint.mjJNT_HINGE)
        joint.armature = inertias[k].armature
        lim = model.joints[k].limits
        if lim is not None and np.all(np.isfinite(lim)):  # MJCF ranges are finite (rad or m)
            joint.range = [v * (scale if model.prismatic[k] else 1.0) for v in lim]
        inert = inertias[k]
        body.explicitinertial = True
        body.mass = inert.mass
        body.ipos = list(inert.com)
        body.fullinertia = inert.fullinertia
        if options.gravity_compensation:
            body.gravcomp = 1.0
        if options.visuals:
            _add_joint_visual(body, model, k, axes[k], options, radius)
        joint_names.append(joint.name)
        parent = body
    return joint_names, parent


def _add_servos(spec: mujoco.MjSpec, joint_names: list[str], options: MJCFOptions) -> None:
    """PD servo per joint as two actuators: position (kp), then rate (kv) set points, so
    ctrl = [n positions, n rates]. With rate set points 0 this is MuJoCo's position actuator
    with damping kv; feeding the reference rates removes the kv * qdot lag."""
    pre = options.prefix
    for k, jname in enumerate(joint_names):
        act = spec.add_actuator(name=f"{pre}servo{k + 1}", target=jname,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=options.kp, kv=0.0)
    if options.kv > 0:
        for k, jname in enumerate(joint_names):
            vel = spec.add_actuator(name=f"{pre}servo{k + 1}_rate", target=jname,
                                    trntype=mujoco.mjtTrn.mjTRN_JOINT)
            vel.set_to_velocity(kv=options.kv)


def _add_hand(last: mujoco.MjsBody, model: Manipulator, options: MJCFOptions, tip: F64,
              radius: float) -> None:
    """The last body vector, the end-effector site and its RGB triad."""
    pre = options.prefix
    if options.visuals and np.linalg.norm(tip) > 1e-9:
        _visual_geom(last, mujoco.mjtGeom.mjGEOM_CAPSULE, _colour(options.link_rgba, options),
                     size=[0.6 * radius, 0, 0], fromto=[0, 0, 0, *tip],
                     name=f"{pre}b{model.n + 1}")
    last.add_site(name=f"{pre}end_effector", pos=list(tip), quat=list(hand_quat(model)),
                  size=[0.5 * radius, 0, 0], rgba=[1.0, 1.0, 1.0, 0.0])
    if options.visuals:
        frame = model.end_effector.frame
        colours = ([0.9, 0.15, 0.15], [0.15, 0.8, 0.15], [0.15, 0.3, 0.95])
        for col, name in enumerate("xyz"):
            d = frame[:, col] * 3.0 * radius
            _visual_geom(last, mujoco.mjtGeom.mjGEOM_CAPSULE,
                         _colour([*colours[col], 1.0], options), size=[0.25 * radius, 0, 0],
                         fromto=[*tip, *(tip + d)], name=f"{pre}hand_{name}", group=1)


def build_spec(model: Manipulator, options: MJCFOptions | None = None) -> mujoco.MjSpec:
    """The :class:`mujoco.MjSpec` of ``model`` (see the module docstring for the layout)."""
    if not isinstance(model, Manipulator):
        raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
    options = options or MJCFOptions()
    scale = metres_per_unit(model.length_unit, "model.length_unit")
    bodies_m = np.asarray(model.bodies) * scale
    reach_m = float(np.sum(np.linalg.norm(bodies_m, axis=1))) or 1.0
    radius = options.link_radius or 0.022 * reach_m
    spec = _new_spec(model, options, reach_m)
    _add_surroundings(spec.worldbody, options, reach_m, radius)
    joint_names, last = _add_links(spec.worldbody, model, options, scale, radius)
    if options.actuators:
        _add_servos(spec, joint_names, options)
    _add_hand(last, model, options, bodies_m[model.n], radius)
    return spec


def joint_name(model: Manipulator, k: int) -> str:
    """MJCF name of joint k (0-based): the model's name if it is a valid MJCF name, else
    ``q<k+1>`` (without the options' prefix)."""
    name = model.joint_names[k]
    return name if NAME_OK.match(name) else f"q{k + 1}"


def build(model: Manipulator, options: MJCFOptions | None = None) -> BuiltArm:
    """Build and compile the MuJoCo model of ``model``.

    Raises:
        InputError: bad options (the message names the option).
        mjcf.MJCFCompileError: MuJoCo refused the model (its message is included).
    """
    options = options or MJCFOptions()
    spec = build_spec(model, options)
    try:
        compiled = spec.compile()
    except ValueError as exc:  # MuJoCo's compiler errors
        raise MJCFCompileError(f"MuJoCo could not compile the model of {model.name!r}: "
                               f"{exc}") from exc
    pre = options.prefix
    jids = [mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, f"{pre}{joint_name(model, k)}")
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
