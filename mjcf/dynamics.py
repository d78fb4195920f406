"""Inverse-dynamics torques along a trajectory (``mj_inverse``), for the motion diagnosis's
``dynamic_compliance`` effect (computed here, passed into the core as an array)."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mjcf.gravity import joint_space_model
from zrp.errors import InputError

__all__ = ["inverse_dynamics_torques", "mode_terms"]

F64 = NDArray[np.float64]


def inverse_dynamics_torques(source: str | Path | mujoco.MjModel, q: ArrayLike, qd: ArrayLike,
                             qdd: ArrayLike, field: str = "path") -> F64:
    """Joint torques that move an MJCF arm along (q, qd, qdd): MuJoCo's ``qfrc_inverse`` from
    ``mj_inverse`` (M(q) qdd + bias(q, qd), gravity included; N m for hinges), shape (S, n).

    The MJCF must have exactly n hinge/slide joints in the model's order with the same zero
    (as the project's MJCF export writes them); constraints are off (no limits or friction
    enter the torques).

    Args:
        source: an MJCF/URDF path or a compiled ``mujoco.MjModel``.
        q, qd, qdd: joint values (rad), velocities (rad/s), accelerations (rad/s^2), shape
            (S, n) each (MuJoCo units: metres for slide joints).
        field: how error messages name ``source``.
    """
    q, qd, qdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q, qd, qdd))
    if not (q.shape == qd.shape == qdd.shape):
        raise InputError(f"q, qd, qdd: expected equal shapes (S, n), got {q.shape}, "
                         f"{qd.shape}, {qdd.shape}")
    m = joint_space_model(source, q.shape[1], field)
    d = mujoco.MjData(m)
    saved = m.opt.disableflags
    m.opt.disableflags = saved | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    out = np.empty(q.shape)
    try:
        for i in range(q.shape[0]):
            d.qpos[:] = q[i]
            d.qvel[:] = qd[i]
            d.qacc[:] = qdd[i]
            mujoco.mj_inverse(m, d)
            out[i] = d.qfrc_inverse
    finally:
        m.opt.disableflags = saved
    return out


def mode_terms(source: str | Path | mujoco.MjModel, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike,
               field: str = "path") -> F64:
    """The arm's own stiffness and damping of each joint per unit inertia along (q, qd, qdd),
    for the motion diagnosis's ``residual_vibration`` (eq. M6 of ``zrp.gap.motion``): with
    f = ``qfrc_inverse``, s_k = (df_k/dq_k) / M_kk (gravity's stiffness and the change of the
    coupling torques with the joint's angle, 1/s^2) and b_k = (df_k/dq'_k) / M_kk (the velocity
    coupling, 1/s), M_kk = df_k/dq''_k; from ``mjd_inverseFD`` (central differences; the
    diagonal entries do not depend on its transposed layout). Shape (S, n, 2): [..., 0] = s,
    [..., 1] = b. Same MJCF requirements as :func:`inverse_dynamics_torques`."""
    q, qd, qdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q, qd, qdd))
    if not (q.shape == qd.shape == qdd.shape):
        raise InputError(f"q, qd, qdd: expected equal shapes (S, n), got {q.shape}, "
                         f"{qd.shape}, {qdd.shape}")
    m = joint_space_model(source, q.shape[1], field)
    d = mujoco.MjData(m)
    saved = m.opt.disableflags
    m.opt.disableflags = saved | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    nv = m.nv
    dq, dv, da = (np.zeros((nv, nv)) for _ in range(3))
    out = np.empty((*q.shape, 2))
    try:
        for i in range(q.shape[0]):
            d.qpos[:] = q[i]
            d.qvel[:] = qd[i]
            d.qacc[:] = qdd[i]
            mujoco.mjd_inverseFD(m, d, 1e-6, False, dq, dv, da, None, None, None, None)
            mkk = np.diag(da)
            ok = mkk > 0.0  # a joint that moves no mass has no mode: its terms stay 0
            out[i, :, 0] = np.divide(np.diag(dq), mkk, out=np.zeros(nv), where=ok)
            out[i, :, 1] = np.divide(np.diag(dv), mkk, out=np.zeros(nv), where=ok)
    finally:
        m.opt.disableflags = saved
    return out
