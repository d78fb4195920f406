"""Gravity torques of a MuJoCo model, for the gap diagnosis's joint-compliance effect."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["gravity_torques", "joint_space_model"]



def joint_space_model(source: str | Path | mujoco.MjModel, n: int,
                      field: str = "path") -> mujoco.MjModel:
    """The compiled MJCF of an arm with exactly ``n`` hinge/slide joints (one per model joint,
    in order, same zero), for torques along joint values; ``field`` names ``source`` in errors.

    Raises:
        InputError: the file does not load, or its joints do not match.
    """
    if isinstance(source, mujoco.MjModel):
        m = source
    else:
        try:
            m = mujoco.MjModel.from_xml_path(str(source))
        except Exception as exc:  # mujoco raises ValueError with its own message
            raise InputError(f"{field} {source}: cannot load: {exc}") from exc
    if m.nq != n or m.nv != n:
        raise InputError(f"{field} {source if isinstance(source, (str, Path)) else ''}: has "
                         f"{m.nq} position coordinates, but the model has {n} joints; the MJCF "
                         "must have one hinge/slide joint per model joint")
    return m


def gravity_torques(path: str | Path, q_pose: ArrayLike, field: str = "path") -> F64:
    """Gravity torque on each joint from an MJCF model's inertias, shape (P, n).

    The MJCF must have exactly n hinge/slide joints in the model's order with the same zero
    (as the project's MJCF export writes them). Returns the generalised force gravity exerts on
    each joint, -``qfrc_bias`` at zero velocity (N m for hinges, in the MJCF's units; positive
    when gravity turns the joint positively).

    Args:
        q_pose: joint values, rad, shape (P, n).
        field: how error messages name ``path`` (the command line passes its option).
    """
    q_pose = np.asarray(q_pose, dtype=float)
    m = joint_space_model(path, q_pose.shape[1], field)
    d = mujoco.MjData(m)
    out = np.empty(q_pose.shape)
    for i, q in enumerate(q_pose):
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        out[i] = -d.qfrc_bias  # the generalised force gravity exerts (qfrc_bias holds it)
    return out
