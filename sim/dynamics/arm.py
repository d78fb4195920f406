"""The arm whose dynamics are diagnosed: a MuJoCo model with one hinge/slide joint per logged
joint, its editable spec (for the corrected model) and the tool body (where a payload sits).

Sources: an MJCF file, a URDF file with inertials (MuJoCo reads URDF directly; its meshes are
stripped here, as the dynamics need only the inertials, and joints off the chain to
``end_link`` are made fixed, e.g. a gripper's fingers), a :class:`mujoco.MjSpec`, or a ZRP
manipulator built with PUMA 560 inertias (:func:`arm_from_manipulator`).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from mjcf import MJCFOptions, build
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator

__all__ = ["Arm", "arm_from_manipulator", "load_arm", "resolve_arm"]

_DOF = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


@dataclass(frozen=True, eq=False)
class Arm:
    """An arm model for the dynamic gap.

    Attributes:
        name: for reports.
        spec: the editable model (the corrected MJCF is written from a copy of it).
        model: the compiled model; dof k is logged joint k.
        tool_body: id of the body carrying the tool (the last moving body).
        tool_point: the payload point in the tool body's frame, m, shape (3,).
    """

    name: str
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    tool_body: int
    tool_point: F64

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
    return int(m.jnt_bodyid[m.njnt - 1]), np.zeros(3)


def _from_spec(spec: mujoco.MjSpec, name: str, tool_site: str | None, field: str) -> Arm:
    try:
        m = spec.compile()
    except ValueError as exc:
        raise InputError(f"{field}: MuJoCo could not compile it: {exc}") from exc
    _check(m, field)
    body, point = _tool(m, tool_site, field)
    return Arm(name, spec, m, body, point)


def _chain_links(root: ET.Element, end_link: str) -> set[str]:
    """Links from the URDF root to ``end_link``."""
    parent = {j.find("child").get("link"): j.find("parent").get("link")
              for j in root.iter("joint") if j.find("child") is not None}
    if end_link not in parent and end_link not in {lk.get("name") for lk in root.iter("link")}:
        raise InputError(f"end_link: no link {end_link!r} in the URDF")
    chain = {end_link}
    while end_link in parent:
        end_link = parent[end_link]
        chain.add(end_link)
    return chain


def strip_urdf(text: str, end_link: str | None = None) -> str:
    """The URDF without visual/collision elements (no meshes to resolve) and, with
    ``end_link``, with every joint off the chain to it made fixed."""
    root = ET.fromstring(text)
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    if end_link is not None:
        chain = _chain_links(root, end_link)
        for j in root.iter("joint"):
            if j.find("child").get("link") not in chain:
                j.set("type", "fixed")
    return ET.tostring(root, encoding="unicode")


def load_arm(source: str | os.PathLike[str] | mujoco.MjSpec, *, end_link: str | None = None,
             tool_site: str | None = None, name: str | None = None) -> Arm:
    """The arm of an MJCF or URDF file (or a spec); see the module docstring.

    Args:
        source: MJCF (.xml) or URDF (.urdf) path, or a :class:`mujoco.MjSpec`.
        end_link: URDF only: the last link of the arm (joints off its chain are fixed).
        tool_site: the site where a payload sits; None: the last joint's body origin.
        name: for reports (default: the file's stem).
    """
    if isinstance(source, mujoco.MjSpec):
        return _from_spec(source, name or "arm", tool_site, "spec")
    path = Path(source)
    if not path.is_file():
        raise InputError(f"model: no such file {str(path)!r} (an MJCF .xml or a URDF)")
    field = f"model {path.name}"
    try:
        if path.suffix.lower() == ".urdf":
            spec = mujoco.MjSpec.from_string(strip_urdf(path.read_text(encoding="utf-8"),
                                                        end_link))
        else:
            spec = mujoco.MjSpec.from_file(str(path))
    except (ValueError, ET.ParseError, OSError) as exc:
        raise InputError(f"{field}: cannot load: {exc}") from exc
    if path.suffix.lower() != ".urdf":
        spec.meshdir = str((path.parent / (spec.meshdir or "")).resolve())
    return _from_spec(spec, name or path.stem, tool_site, field)


def arm_from_manipulator(model: Manipulator, inertia: str = "puma560") -> Arm:
    """A ZRP manipulator built into MuJoCo (:func:`mjcf.build`) with ``inertia`` ("puma560"
    or "rods") and no servos; the payload sits at its end-effector site."""
    built = build(model, MJCFOptions(inertia=inertia))
    spec = built.spec
    for act in list(spec.actuators):
        spec.delete(act)
    return _from_spec(spec, model.name, built.site_name, f"manipulator {model.name}")


def resolve_arm(model: str, *, end_link: str | None = None, tool_site: str | None = None
                ) -> Arm:
    """The arm of a command line's ``--model``: an MJCF (.xml) or URDF (.urdf) file, else a
    ZRP model (builtin name or .toml) built with PUMA 560 inertias (6R) or rods."""
    if Path(model).suffix.lower() in (".xml", ".urdf", ".mjcf"):
        return load_arm(model, end_link=end_link, tool_site=tool_site)
    m = load_model(model)
    six_r = m.n == 6 and not np.asarray(m.prismatic).any()
    return arm_from_manipulator(m, "puma560" if six_r else "rods")
