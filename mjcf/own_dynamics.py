"""An arm's own mass properties and joint dynamics, read from its shipped URDF or MJCF and laid
out joint by joint for a ZRP model of the same arm.

The file is compiled by :func:`mjcf.shipped.load_shipped`. At qpos = 0 (the ZRP zero reference,
as :mod:`mjcf.importer` defines it) every body of the file belongs to the nearest chain joint
above it (its own joint, or the last chain joint of an ancestor): body k of the chain carries
link k and everything rigidly attached to it (covers, motors, the hand and its fingers at
their zero, the tool). Bodies above joint 1 are the fixed base and do not move. Each group is
lumped into one :class:`mjcf.inertia.BodyInertia` in world-aligned axes (the layout of
:mod:`mjcf.builder`): with the body masses m_b, centres x_b and world inertia tensors
I_b = R_b diag(I_principal) R_b^T,

    m = sum m_b,   c = sum m_b x_b / m,
    I_c = sum [ I_b + m_b (|r_b|^2 E - r_b r_b^T) ],   r_b = x_b - c          (eq D1)

(the parallel-axis theorem), and the centre of mass is stored relative to the ZRP model's
point on joint k. Joint damping, Coulomb friction (``frictionloss``) and armature are those of
the file (MuJoCo's URDF reader maps ``<dynamics damping= friction=>``).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from mjcf.errors import MJCFImportError
from mjcf.inertia import BodyInertia
from mjcf.shipped import load_shipped
from zrp.arrays import F64
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = ["MASSLESS_LINK", "ArmDynamics", "arm_dynamics", "file_sha256"]

#: (kg, kg m^2) given to a chain link the file leaves without mass (MuJoCo needs a moving body
#: to have some); far below any real link, it changes no torque beyond 1e-5 N m.
MASSLESS_LINK = (1e-6, 1e-9)
_AXIS_TOL = 1e-6      # |u_file x u_model|
_ANCHOR_TOL_M = 1e-6  # distance of the file's joint axis from the model's point on joint k


@dataclass(frozen=True, eq=False)
class ArmDynamics:
    """What a shipped file says about the arm's dynamics, per joint of the ZRP model.

    Attributes:
        source: the file read.
        inertias: link k's lumped mass properties (eq D1), metres, world-aligned axes, centre
            of mass relative to the model's point on joint k; shape (n,).
        damping: viscous damping per joint, N m s/rad (N s/m), shape (n,).
        friction: Coulomb friction per joint, N m (N), shape (n,).
        armature: rotor inertia per joint, kg m^2 (kg), shape (n,).
        massless: 1-based joints whose link the file leaves without mass (given
            :data:`MASSLESS_LINK`).
        sha256: SHA-256 (hex) of the file's bytes as read: a later run rebuilding this robot
            (``zrp verify`` from a truth file) checks it is the same file.
    """

    source: str
    inertias: tuple[BodyInertia, ...]
    damping: F64
    friction: F64
    armature: F64
    massless: tuple[int, ...] = ()
    sha256: str = ""

    def summary(self) -> str:
        """One line for a report: the file, the total moving mass."""
        mass = sum(b.mass for b in self.inertias)
        return f"own inertias from {Path(self.source).name} ({mass:.2f} kg moving)"


def _chain_joint_ids(m: mujoco.MjModel, model: Manipulator, source: str) -> list[int]:
    """The file's joint for each model joint, by name."""
    ids = []
    for k, j in enumerate(model.joints):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name) if j.name else -1
        if jid < 0:
            raise MJCFImportError(
                f"joint {k + 1} ({j.name or 'unnamed'}): no joint of that name in {source}; the "
                "model and the file must name the same joints (import the model from the file)")
        ids.append(int(jid))
    return ids


def _check_geometry(d: mujoco.MjData, jids: list[int], model: Manipulator, scale: float,
                    source: str) -> F64:
    """The model's points on the joints (world, m, shape (n, 3)), checked against the file's
    joint axes at qpos = 0."""
    points = np.cumsum(np.asarray(model.bodies)[:-1], axis=0) * scale
    for k, jid in enumerate(jids):
        u = np.asarray(model.axes[k])
        if np.linalg.norm(np.cross(d.xaxis[jid], u)) > _AXIS_TOL:
            raise MJCFImportError(f"joint {k + 1} ({model.joints[k].name}): its axis in "
                                  f"{source} {d.xaxis[jid].round(6).tolist()} is not the "
                                  f"model's {u.round(6).tolist()}; not the same arm")
        off = np.linalg.norm(np.cross(d.xanchor[jid] - points[k], u))
        if off > _ANCHOR_TOL_M + 1e-9 * np.linalg.norm(points[k]):
            raise MJCFImportError(f"joint {k + 1} ({model.joints[k].name}): its axis in "
                                  f"{source} passes {off * 1e3:.4g} mm from the model's; not "
                                  "the same arm (or another base frame)")
    return points


def _owners(m: mujoco.MjModel, jids: list[int]) -> F64:
    """For each body, the index k of the chain joint that carries it, -1 for the base."""
    carrier = {int(m.jnt_bodyid[j]): k for k, j in enumerate(jids)}  # last joint of a body
    owner = np.full(m.nbody, -1)
    for b in range(1, m.nbody):  # parents come before children in MuJoCo's body order
        owner[b] = carrier.get(b, owner[m.body_parentid[b]])
    return owner


def _lump(d: mujoco.MjData, m: mujoco.MjModel, bodies: F64, point: F64, armature: float
          ) -> BodyInertia | None:
    """Eq D1 over ``bodies``; None when they have no mass."""
    mass = m.body_mass[bodies]
    total = float(mass.sum())
    if total <= 0:
        return None
    x = d.xipos[bodies]
    c = mass @ x / total
    inertia = np.zeros((3, 3))
    for b, mb, xb in zip(bodies, mass, x, strict=True):
        r = xb - c
        rot = d.ximat[b].reshape(3, 3)
        inertia += rot @ np.diag(m.body_inertia[b]) @ rot.T \
            + mb * (float(r @ r) * np.eye(3) - np.outer(r, r))
    return BodyInertia(mass=total, com=c - point, inertia=0.5 * (inertia + inertia.T),
                       armature=armature)


def arm_dynamics(path: str | os.PathLike[str], model: Manipulator) -> ArmDynamics:
    """Read the arm's own dynamics from its shipped URDF/MJCF for ``model`` (module docstring).

    Args:
        path: the ``.urdf`` or MJCF file the model was imported from (or one naming the same
            joints with the same geometry).
        model: the ZRP model; its joints are found in the file by name.

    Raises:
        MJCFImportError: the file does not compile, lacks a joint of the model, or its joint
            axes are not the model's at the zero reference (a named joint).
    """
    source = str(path)
    digest = file_sha256(path)
    m = load_shipped(path)
    jids = _chain_joint_ids(m, model, source)
    d = mujoco.MjData(m)
    d.qpos[:] = 0.0
    mujoco.mj_kinematics(m, d)
    scale = metres_per_unit(model.length_unit, "model.length_unit")
    points = _check_geometry(d, jids, model, scale, source)
    owner = _owners(m, jids)
    dofs = [int(m.jnt_dofadr[j]) for j in jids]
    inertias, massless = [], []
    for k in range(model.n):
        arm = float(m.dof_armature[dofs[k]])
        lumped = _lump(d, m, np.flatnonzero(owner == k), points[k], arm)
        if lumped is None:
            massless.append(k + 1)
            mass, tiny = MASSLESS_LINK
            lumped = BodyInertia(mass=mass, com=np.zeros(3), inertia=tiny * np.eye(3),
                                 armature=arm)
        inertias.append(lumped)
    return ArmDynamics(source, tuple(inertias), m.dof_damping[dofs].copy(),
                       m.dof_frictionloss[dofs].copy(), m.dof_armature[dofs].copy(),
                       tuple(massless), digest)


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of a file's bytes; "" when it cannot be read (the loader names that)."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return ""
    return h.hexdigest()
