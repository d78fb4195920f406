"""The arm whose dynamics are diagnosed: a MuJoCo model with one hinge/slide joint per logged
joint, its editable spec (for the corrected model) and the tool body (where a payload sits).

Sources: an MJCF file, a URDF file with inertials (both read by
:func:`mjcf.load_shipped_spec`: inertials, limits, damping and friction kept, ``package://``
meshes resolved or dropped), a :class:`mujoco.MjSpec`, or a ZRP manipulator built with PUMA
560 inertias (:func:`arm_from_manipulator`).

A file may be a whole robot (a mobile base with wheels, a torso, a head, antennas, two arms,
fingers): with ``end_link`` the arm is the chain of moving joints from the model's root to
``end_link``, and every other moving joint is made fixed (what hangs on the chain, e.g. a
gripper, stays as mass on its link; what is elsewhere, e.g. the wheels, is welded to the
fixed base and does not enter the arm's torques). A floating or planar joint (a mobile
base's, MuJoCo's free joint) is made fixed: the base is fixed. Continuous joints are hinges
without limits. A URDF's inertials MuJoCo would refuse (point masses, massless moving links,
inertias not positive definite or violating the triangle inequality) are repaired or, off
the arm, left out (:mod:`mjcf.inertials`). Every such change is said in :attr:`Arm.notes`.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from mjcf.actuator_limits import actuator_torque_limits
from mjcf.attachments import find_attachments
from mjcf.builder import MJCFOptions, build
from mjcf.errors import MJCFImportError
from mjcf.inertials import kinematic_copy, repair_inertials
from mjcf.inverse import body_params, gravity_torques, inverse_dynamics, regressor
from mjcf.shipped import load_shipped_spec
from zrp.arrays import F64
from zrp.errors import InputError, ModelFileError
from zrp.gap.dynamics.arm import Attachment
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.model.urdf import read_urdf
from zrp.units import metres_per_unit

__all__ = ["Arm", "arm_from_manipulator", "load_arm", "resolve_arm", "urdf_velocity_limits"]

_DOF = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


@dataclass(frozen=True, eq=False)
class Arm:
    """An arm model for the dynamic gap (MuJoCo's implementation of
    :class:`zrp.gap.dynamics.arm.DynamicArm`).

    Attributes:
        name: for reports.
        spec: the editable model (the corrected MJCF is written from a copy of it).
        model: the compiled model; dof k is logged joint k.
        tool_body: id of the body carrying the tool (the last moving body).
        tool_point: the payload point in the tool body's frame, m, shape (3,).
        attachments: the parts carried rigidly on the tool body (:mod:`mjcf.attachments`).
        notes: what loading did to the file's model, in words (joints made fixed).
        velocity: the source's joint velocity limits, rad/s (m/s), shape (n,), inf where none
            (MuJoCo keeps none: a URDF's ``<limit velocity=>``, a ZRP model's
            ``velocity_limit``), or None: none known.
    """

    name: str
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    tool_body: int
    tool_point: F64
    attachments: tuple[Attachment, ...] = ()
    notes: tuple[str, ...] = ()
    velocity: F64 | None = None

    @property
    def n(self) -> int:
        return int(self.model.nv)

    @property
    def joint_names(self) -> list[str]:
        m = self.model
        return [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, k) or f"joint{k + 1}"
                for k in range(m.njnt)]

    def moving_bodies(self) -> list[int]:
        """Ids of the bodies that move with some joint (their inertias enter the torques)."""
        m = self.model
        return [b for b in range(1, m.nbody) if m.body_weldid[b] != 0 and m.body_mass[b] >= 0]

    def body_name(self, b: int) -> str:
        return mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}"

    def body_params(self, b: int) -> F64:
        return body_params(self.model, b)

    def joint_terms(self) -> tuple[F64, F64, F64]:
        m = self.model
        return (np.array(m.dof_frictionloss, dtype=float), np.array(m.dof_damping, dtype=float),
                np.array(m.dof_armature, dtype=float))

    def position_limits(self) -> tuple[F64, F64]:
        m = self.model
        lim = np.array(m.jnt_range, dtype=float)
        limited = np.array(m.jnt_limited, dtype=bool) & (lim[:, 1] > lim[:, 0])
        return (np.where(limited, lim[:, 0], -np.inf), np.where(limited, lim[:, 1], np.inf))

    def velocity_limits(self) -> F64:
        if self.velocity is None:
            return np.full(self.n, np.inf)
        return np.array(self.velocity, dtype=float)

    def revolute(self) -> NDArray[np.bool_]:
        return np.array(self.model.jnt_type, dtype=int) == int(mujoco.mjtJoint.mjJNT_HINGE)

    def torque_limits(self) -> F64:
        """Every limit the model states (:mod:`mjcf.actuator_limits`): the joint's
        actuatorfrcrange (a URDF's effort), its actuators' forcerange and a motor's ctrlrange,
        times gear; inf where none."""
        return actuator_torque_limits(self.model)[0]

    def inverse_dynamics(self, q: F64, qd: F64, qdd: F64) -> F64:
        return inverse_dynamics(self.model, q, qd, qdd)

    def gravity_torques(self, q: F64) -> F64:
        return gravity_torques(self.model, q)

    def regressor(self, q: F64, qd: F64, qdd: F64, bodies: Iterable[int] | None = None
                  ) -> tuple[F64, list[tuple[int, str]]]:
        chosen = self.moving_bodies() if bodies is None else list(bodies)
        return regressor(self.model, chosen, q, qd, qdd)


def _check(m: mujoco.MjModel, field: str) -> None:
    bad = [k for k in range(m.njnt) if int(m.jnt_type[k]) not in _DOF]
    if bad or m.nq != m.nv or m.nv == 0:
        raise InputError(f"{field}: the dynamic gap needs an arm of hinge/slide joints only; "
                         f"this model has {m.njnt} joints, nq = {m.nq}, nv = {m.nv} (a free or "
                         "ball joint, or no joint): fix the base and lock other joints")


def _tool(m: mujoco.MjModel, tool_site: str | None, field: str) -> tuple[int, F64]:
    if tool_site is not None:
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, tool_site)
        if sid < 0:
            raise InputError(f"tool_site: no site {tool_site!r} in {field}")
        return int(m.site_bodyid[sid]), np.array(m.site_pos[sid], dtype=float)
    return _end_body(m), np.zeros(3)


def _ancestors(m: mujoco.MjModel, b: int) -> list[int]:
    out = [b]
    while b > 0:
        b = int(m.body_parentid[b])
        out.append(b)
    return out


def _end_body(m: mujoco.MjModel) -> int:
    """The arm's last link: the last joint's body, or, when the joints end in branches (a
    gripper's fingers, each on its own joint), the body they all hang from (the hand's link),
    so that a payload never sits on a finger."""
    bodies = {int(m.jnt_bodyid[k]) for k in range(m.njnt)}
    leaves = [b for b in bodies if not any(b in _ancestors(m, c)[1:] for c in bodies)]
    common = set(_ancestors(m, leaves[0]))
    for b in leaves[1:]:
        common &= set(_ancestors(m, b))
    end = max(common, key=lambda b: len(_ancestors(m, b)))
    return end if end > 0 else int(m.jnt_bodyid[m.njnt - 1])


def _from_spec(spec: mujoco.MjSpec, name: str, tool_site: str | None, field: str,
               notes: tuple[str, ...] = (), velocity: dict[str, float] | None = None) -> Arm:
    parts = find_attachments(spec, tool_site)  # before static bodies are fused
    try:
        m = spec.compile()
    except ValueError as exc:
        raise InputError(f"{field}: MuJoCo could not compile it: {exc}") from exc
    _check(m, field)
    body, point = _tool(m, tool_site, field)
    vel = None
    if velocity is not None:
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, k) for k in range(m.njnt)]
        vel = np.array([velocity.get(j or "", np.inf) for j in names])
    return Arm(name, spec, m, body, point, parts, notes, vel)


def urdf_velocity_limits(path: Path) -> dict[str, float]:
    """The ``<limit velocity=>`` of each joint of a URDF (MuJoCo's URDF reader drops them),
    by joint name; a velocity of 0 or none is left out (unknown)."""
    tree = read_urdf(path)
    return {j.name: float(j.velocity_limit) for j in tree.joints.values()
            if j.velocity_limit is not None}


def _chain_end(spec: mujoco.MjSpec, n_joints: int, field: str) -> str | None:
    """The body of the model's ``n_joints``-th joint when the model has more joints than the
    log and its first ``n_joints`` form one chain (the rest, e.g. a gripper's fingers, hang
    off its end); None otherwise."""
    try:
        m = kinematic_copy(spec)  # the joints' order, whatever the inertials
    except ValueError as exc:
        raise InputError(f"{field}: MuJoCo could not compile it: {exc}") from exc
    if m.njnt <= n_joints or n_joints < 1:
        return None
    bodies = [int(m.jnt_bodyid[k]) for k in range(n_joints)]
    for a, b in itertools.pairwise(bodies):
        up = b
        while up not in (a, 0):
            up = int(m.body_parentid[up])
        if up != a:
            return None
    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, bodies[-1])


def _fix_off_chain(spec: mujoco.MjSpec, end_link: str) -> list[str]:
    """Make every joint off the chain from the root to body ``end_link`` fixed (delete it:
    its body is then welded to its parent), with the equality constraints on it (a URDF
    ``<mimic>``, e.g. a gripper's second finger), the actuators driving it and the keyframes
    (an MJCF's); the names of the joints made fixed."""
    end = spec.body(end_link)
    if end is None:
        raise InputError(f"end_link: no link (body) {end_link!r} in the model")
    chain = {end.name}
    while end.parent is not None and end.parent.name != end.name:
        end = end.parent
        chain.add(end.name)
    off = [j.name for j in spec.joints if j.parent.name not in chain]
    _delete_joints(spec, set(off))
    return off


def _delete_joints(spec: mujoco.MjSpec, names: set[str]) -> None:
    """Delete the joints ``names``, the equality constraints on them, the actuators driving
    them and (when any joint goes) the keyframes, whose qpos no longer fit."""
    for eq in list(spec.equalities):
        if eq.name1 in names or eq.name2 in names:
            spec.delete(eq)
    for act in list(spec.actuators):  # an MJCF's motor on a joint made fixed (issue 44)
        if act.target in names:
            spec.delete(act)
    for key in list(spec.keys) if names else []:
        spec.delete(key)
    for j in list(spec.joints):
        if j.name in names:
            spec.delete(j)


def _fix_base(spec: mujoco.MjSpec, path: Path) -> tuple[str, ...]:
    """Make the free joints of ``spec`` and a URDF's floating and planar joints (MuJoCo's
    ``NAME_TX``, ``NAME_TY``, ``NAME_RZ``) fixed: a mobile base becomes a fixed base."""
    planar: set[str] = set()
    if path.suffix.lower() == ".urdf":
        try:
            tree = read_urdf(path)
        except ModelFileError:
            tree = None  # its joints are read again (velocity limits), and said there
        for j in tree.joints.values() if tree is not None else ():
            if j.type in ("floating", "planar"):
                planar |= {j.name, f"{j.name}_TX", f"{j.name}_TY", f"{j.name}_RZ"}
    free = int(mujoco.mjtJoint.mjJNT_FREE)
    names = [j.name for j in spec.joints if j.name in planar or int(j.type) == free]
    if not names:
        return ()
    _delete_joints(spec, set(names))
    return (f"the floating/planar joint(s) {', '.join(map(repr, names))} (a mobile base) "
            "are made fixed: the base is fixed",)


def _urdf_inertials(spec: mujoco.MjSpec, field: str) -> tuple[str, ...]:
    try:
        return repair_inertials(spec)
    except MJCFImportError as exc:
        raise InputError(f"{field}: {exc}") from exc


def load_arm(source: str | os.PathLike[str] | mujoco.MjSpec, *, end_link: str | None = None,
             tool_site: str | None = None, name: str | None = None,
             n_joints: int | None = None) -> Arm:
    """The arm of an MJCF or URDF file (or a spec); see the module docstring.

    Args:
        source: MJCF (.xml) or URDF (.urdf) path, or a :class:`mujoco.MjSpec`.
        end_link: the last link (body) of the arm: joints off its chain from the root are
            made fixed (a whole robot's wheels, head, other arm, fingers).
        tool_site: the site where a payload sits; None: the last joint's body origin.
        name: for reports (default: the file's stem).
        n_joints: the joints the log has: a model with more, whose first ``n_joints`` form a
            chain (a gripper's fingers beyond it), has the others made fixed (said in
            :attr:`Arm.notes`) when no ``end_link`` is given.
    """
    if isinstance(source, mujoco.MjSpec):
        return _from_spec(source, name or "arm", tool_site, "spec")
    path = Path(source)
    if not path.is_file():
        raise InputError(f"model: no such file {str(path)!r} (an MJCF .xml or a URDF)")
    field = f"model {path.name}"
    try:
        spec = load_shipped_spec(path)
    except MJCFImportError as exc:
        raise InputError(f"{field}: cannot load: {exc}") from exc
    notes = _fix_base(spec, path)
    if end_link is None and n_joints is not None:
        end_link = _chain_end(spec, n_joints, field)
        if end_link is not None:
            notes += (f"the model has more joints than the log's {n_joints}: joints after "
                      f"link {end_link!r} (e.g. a gripper's fingers) are made fixed",)
    if end_link is not None:
        off = _fix_off_chain(spec, end_link)
        if off:
            notes += (f"the arm is the chain from the root to link {end_link!r}; the other "
                      f"moving joints are made fixed: {', '.join(off)}",)
    velocity = None
    if path.suffix.lower() == ".urdf":
        notes += _urdf_inertials(spec, field)
        try:
            velocity = urdf_velocity_limits(path)
        except ModelFileError as exc:
            notes += (f"the URDF's velocity limits could not be read ({exc}): none known",)
        # one body per moving link (MuJoCo's URDF default): links on fixed joints (a flange,
        # a hand, fingers made fixed) fuse into their parent, as the inertial regressor has
        # one set of 10 parameters per body
        spec.compiler.fusestatic = True
    return _from_spec(spec, name or path.stem, tool_site, field, notes, velocity)


def arm_from_manipulator(model: Manipulator, inertia: str = "puma560") -> Arm:
    """A ZRP manipulator built into MuJoCo (:func:`mjcf.build`) with ``inertia`` ("puma560"
    or "rods") and no servos; the payload sits at its end-effector site."""
    built = build(model, MJCFOptions(inertia=inertia))
    spec = built.spec
    for act in list(spec.actuators):
        spec.delete(act)
    arm = _from_spec(spec, model.name, built.site_name, f"manipulator {model.name}")
    m_per = metres_per_unit(model.length_unit)
    vel = [np.inf if j.velocity_limit is None else
           j.velocity_limit * (m_per if j.is_prismatic else 1.0) for j in model.joints]
    return dataclasses.replace(arm, velocity=np.array(vel, dtype=float))


def resolve_arm(model: str, *, end_link: str | None = None, tool_site: str | None = None,
                n_joints: int | None = None) -> Arm:
    """The arm of a command line's ``--model``: an MJCF (.xml) or URDF (.urdf) file, else a
    ZRP model (builtin name or .toml) built with PUMA 560 inertias (6R) or rods."""
    if Path(model).suffix.lower() in (".xml", ".urdf", ".mjcf"):
        return load_arm(model, end_link=end_link, tool_site=tool_site, n_joints=n_joints)
    m = load_model(model)
    six_r = m.n == 6 and not np.asarray(m.prismatic).any()
    return arm_from_manipulator(m, "puma560" if six_r else "rods")
