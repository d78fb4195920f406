"""Inverse-dynamics torques along a trajectory (``mj_inverse``), for the motion diagnosis's
``dynamic_compliance`` effect (computed here, passed into the core as an array)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf.gravity import joint_space_model
from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["inverse_dynamics_torques", "mode_terms"]



def _states(q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> tuple[F64, F64, F64]:
    """q, qd, qdd as float arrays of one shape (S, n) each, or raise naming all three."""
    q, qd, qdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q, qd, qdd))
    if not (q.shape == qd.shape == qdd.shape):
        raise InputError(f"q, qd, qdd: expected equal shapes (S, n), got {q.shape}, "
                         f"{qd.shape}, {qdd.shape}")
    return q, qd, qdd


@contextmanager
def _unconstrained(source: str | Path | mujoco.MjModel, q: F64, qd: F64, qdd: F64, field: str
                   ) -> Iterator[tuple[mujoco.MjModel, Iterator[tuple[int, mujoco.MjData]]]]:
    """The joint-space model of ``source`` with constraints off (no limits or friction; the
    flags are restored on exit) and the samples (i, data) with the data's qpos, qvel, qacc
    set to sample i of ``q``, ``qd``, ``qdd`` (shape (S, n) each, from :func:`_states`)."""
    m = joint_space_model(source, q.shape[1], field)
    d = mujoco.MjData(m)

    def samples() -> Iterator[tuple[int, mujoco.MjData]]:
        for i in range(q.shape[0]):
            d.qpos[:] = q[i]
            d.qvel[:] = qd[i]
            d.qacc[:] = qdd[i]
            yield i, d

    saved = m.opt.disableflags
    m.opt.disableflags = saved | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    try:
        yield m, samples()
    finally:
        m.opt.disableflags = saved


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
    q, qd, qdd = _states(q, qd, qdd)
    out = np.empty(q.shape)
    with _unconstrained(source, q, qd, qdd, field) as (m, samples):
        for i, d in samples:
            mujoco.mj_inverse(m, d)
            out[i] = d.qfrc_inverse
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
    q, qd, qdd = _states(q, qd, qdd)
    out = np.empty((*q.shape, 2))
    with _unconstrained(source, q, qd, qdd, field) as (m, samples):
        nv = m.nv
        dq, dv, da = (np.zeros((nv, nv)) for _ in range(3))
        for i, d in samples:
            mujoco.mjd_inverseFD(m, d, 1e-6, False, dq, dv, da, None, None, None, None)
            mkk = np.diag(da)
            ok = mkk > 0.0  # a joint that moves no mass has no mode: its terms stay 0
            out[i, :, 0] = np.divide(np.diag(dq), mkk, out=np.zeros(nv), where=ok)
            out[i, :, 1] = np.divide(np.diag(dv), mkk, out=np.zeros(nv), where=ok)
    return out
