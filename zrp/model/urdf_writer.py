"""Write any model (nominal, perturbed or calibrated) as a kinematic URDF.

Links ``base``, ``link1``..``linkn`` and ``tool``; every joint frame is parallel to the base
frame at q = 0, so joint k's ``origin`` is b_{k,0} (in metres, no rotation) and its ``axis`` is
u_{k,0}; the fixed joint ``tool_joint`` carries b_{n+1,0} and the hand frame (columns
u_t x u_a, u_t, u_a) as roll-pitch-yaw; the robot's name is made a valid XML name
(:func:`robot_name`). Limited revolute joints are ``revolute``, unlimited
ones ``continuous``; prismatic joints carry their limits when they have them. No geometry is
written, and each moving link gets a nominal 1 g mass only so that MuJoCo loads the file (a
kinematic description; a ``<mujoco>`` element keeps MuJoCo from fusing the tool link).
:func:`zrp.model.urdf.import_urdf` reads it back exactly; Pinocchio and MuJoCo give the same
forward kinematics. For a robot that came from a URDF, :func:`zrp.model.urdf_patch.patch_urdf`
writes that file back with the new geometry instead (its links, names, inertias and meshes
kept).
"""

from __future__ import annotations

import re
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
from scipy.spatial.transform import Rotation

from zrp.errors import ModelError
from zrp.model.manipulator import Manipulator
from zrp.output import write_text
from zrp.units import metres_per_unit

__all__ = ["robot_name", "save_urdf", "urdf_xml"]


#: A nominal 1 g point-like mass per moving link: MuJoCo refuses massless moving bodies.
_INERTIAL = ('<inertial><mass value="0.001"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" '
             'iyz="0" izz="1e-6"/></inertial>')


def _num(x: float) -> str:
    return repr(float(x))


def _vec(v: np.ndarray) -> str:
    return " ".join(_num(x) for x in v)


def _limit(model: Manipulator, k: int, scale: float) -> str:
    j = model.joints[k]
    s = scale if j.is_prismatic else 1.0
    vel = _num(j.velocity_limit * s) if j.velocity_limit is not None else "0"
    if j.limits is None or not np.all(np.isfinite(j.limits)):
        if j.limits is not None:
            raise ModelError(f"joint {k + 1} ({model.joint_names[k]}) limits: URDF limits are "
                             f"finite, got {list(j.limits)}")
        return f'    <limit effort="0" velocity="{vel}"/>\n' if j.is_prismatic else ""
    return (f'    <limit lower="{_num(j.limits[0] * s)}" upper="{_num(j.limits[1] * s)}" '
            f'effort="0" velocity="{vel}"/>\n')


def robot_name(name: str) -> str:
    """A valid URDF robot name (an XML name: letters, digits, ``_``, ``-``, ``.``, not
    starting with a digit, ``-`` or ``.``) for a model's name: every other run of characters
    becomes one ``_`` ("ABB IRB 120 (calibrated)" -> "ABB_IRB_120_calibrated")."""
    out = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_")
    return out if out and re.match(r"[A-Za-z_]", out) else f"robot_{out}".rstrip("_")


def urdf_xml(model: Manipulator) -> str:
    """URDF text of ``model`` (lengths converted to metres).

    Raises:
        ModelError: joint names that repeat, or a half-infinite limit.
    """
    names = model.joint_names
    if len(set(names)) != len(names):
        raise ModelError(f"joint names: must be unique in a URDF, got {list(names)}")
    scale = metres_per_unit(model.length_unit)
    out = [f'<?xml version="1.0"?>\n<robot name={quoteattr(robot_name(model.name))}>\n',
           '  <mujoco><compiler fusestatic="false"/></mujoco>\n',  # keep the tool body
           '  <link name="base"/>\n']
    out += [f'  <link name="link{k}">{_INERTIAL}</link>\n' for k in range(1, model.n + 1)]
    out.append('  <link name="tool"/>\n')
    for k, j in enumerate(model.joints):
        kind = "prismatic" if j.is_prismatic else (
            "revolute" if j.limits is not None else "continuous")
        parent = "base" if k == 0 else f"link{k}"
        out.append(
            f'  <joint name={quoteattr(names[k])} type="{kind}">\n'
            f'    <parent link="{parent}"/>\n    <child link="link{k + 1}"/>\n'
            f'    <origin xyz="{_vec(j.body * scale)}" rpy="0 0 0"/>\n'
            f'    <axis xyz="{_vec(j.axis)}"/>\n' + _limit(model, k, scale) + '  </joint>\n')
    ee = model.end_effector
    rpy = Rotation.from_matrix(ee.frame).as_euler("xyz")  # extrinsic x-y-z = URDF rpy
    out.append(f'  <joint name="tool_joint" type="fixed">\n    <parent link="link{model.n}"/>\n'
               f'    <child link="tool"/>\n'
               f'    <origin xyz="{_vec(ee.body * scale)}" rpy="{_vec(rpy)}"/>\n  </joint>\n')
    out.append("</robot>\n")
    return "".join(out)


def save_urdf(model: Manipulator, path: str | Path, *, overwrite: bool = False) -> Path:
    """Write :func:`urdf_xml` to ``path`` (atomically, :mod:`zrp.output`).

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
    """
    return write_text(path, urdf_xml(model), overwrite=overwrite)
