"""Gravity torques of a MuJoCo model, for the gap diagnosis's joint-compliance effect.

The model is an MJCF the toolkit wrote (one hinge/slide joint per model joint, in order) or an
arm's shipped URDF/MJCF (:func:`mjcf.load_shipped`: ``package://`` meshes resolved or
dropped); a shipped file with more joints than the model (a gripper's fingers) is read through
the model's joint names, the other joints held at their zero.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf.shipped import load_shipped
from zrp.arrays import F64
from zrp.errors import InputError, ZRPError

__all__ = ["gravity_torques", "joint_space_model"]



def joint_space_model(source: str | Path | mujoco.MjModel, n: int,
                      field: str = "path") -> mujoco.MjModel:
    """The compiled MJCF of an arm with exactly ``n`` hinge/slide joints (one per model joint,
    in order, same zero), for torques along joint values; ``field`` names ``source`` in errors.

    Raises:
        InputError: the file does not load, or its joints do not match.
    """
    m = _load(source, field)
    if m.nq != n or m.nv != n:
        raise InputError(f"{field} {source if isinstance(source, (str, Path)) else ''}: has "
                         f"{m.nq} position coordinates, but the model has {n} joints; the MJCF "
                         "must have one hinge/slide joint per model joint")
    return m


def _load(source: str | Path | mujoco.MjModel, field: str) -> mujoco.MjModel:
    if isinstance(source, mujoco.MjModel):
        return source
    try:
        return load_shipped(source)
    except ZRPError as exc:  # the loader names the file and MuJoCo's reason
        raise InputError(f"{field}: {exc}") from exc


def _by_name(m: mujoco.MjModel, names: Sequence[str], source: object, field: str
             ) -> tuple[list[int], list[int]]:
    """(qpos addresses, dof addresses) of the joints ``names`` in ``m``."""
    qadr, dadr = [], []
    for k, name in enumerate(names):
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name) if name else -1
        if j < 0 or int(m.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                                 int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise InputError(f"{field} {source}: joint {k + 1} ({name or 'unnamed'}) of the "
                             "model is not a hinge/slide joint of the file; the file must "
                             "have one per model joint, in order, or name them as the model")
        qadr.append(int(m.jnt_qposadr[j]))
        dadr.append(int(m.jnt_dofadr[j]))
    return qadr, dadr


def gravity_torques(path: str | Path, q_pose: ArrayLike, field: str = "path",
                    joint_names: Sequence[str] | None = None) -> F64:
    """Gravity torque on each joint from an MJCF/URDF model's inertias, shape (P, n).

    The file has exactly n hinge/slide joints in the model's order with the same zero (as the
    project's MJCF export writes them), or, with ``joint_names``, joints of those names (any
    others, e.g. fingers, held at zero: an arm's shipped URDF). Returns the generalised force
    gravity exerts on each joint, -``qfrc_bias`` at zero velocity (N m for hinges, in the
    file's units; positive when gravity turns the joint positively).

    Args:
        q_pose: joint values, rad, shape (P, n).
        field: how error messages name ``path`` (the command line passes its option).
        joint_names: the model's joint names (``[j.name for j in model.joints]``).
    """
    q_pose = np.asarray(q_pose, dtype=float)
    n = q_pose.shape[1]
    m = _load(path, field)
    if joint_names is not None and (m.nq != n or m.nv != n):
        qadr, dadr = _by_name(m, joint_names, path, field)
    else:
        if m.nq != n or m.nv != n:
            raise InputError(f"{field} {path}: has {m.nq} position coordinates, but the model "
                             f"has {n} joints; the file must have one hinge/slide joint per "
                             "model joint (or pass joint_names)")
        qadr = dadr = list(range(n))
    d = mujoco.MjData(m)
    out = np.empty(q_pose.shape)
    for i, q in enumerate(q_pose):
        d.qpos[:] = 0.0
        d.qpos[qadr] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        out[i] = -d.qfrc_bias[dadr]  # the generalised force gravity exerts (qfrc_bias)
    return out
