"""What only MuJoCo computes for the dynamic gap: inverse dynamics along a log, gravity
torques, and the regressor in the link inertial parameters (eqs. R1-R3 of
:mod:`zrp.gap.dynamics.inertia`), on a compiled :class:`mujoco.MjModel`.

Column j of the regressor Y is exactly (tau(phi0 + d e_j) - tau(phi0)) / d for any step d
(eq. R3): ``mj_inverse`` on the model with one parameter changed, no finite-difference error.
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.inertia import PARAM_NAMES, V_EPS, inertia_matrix, skew2

__all__ = ["body_params", "gravity_torques", "inverse_dynamics", "principal_inertia",
           "regressor", "set_body_params"]


def body_params(m: mujoco.MjModel, b: int) -> F64:
    """phi_b of body ``b`` (eq. R1)."""
    mass = float(m.body_mass[b])
    c = np.array(m.body_ipos[b], dtype=float)
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, m.body_iquat[b])
    r = rot.reshape(3, 3)
    io = r @ np.diag(m.body_inertia[b]) @ r.T + mass * skew2(c)
    return np.array([mass, *(mass * c), io[0, 0], io[1, 1], io[2, 2], io[0, 1], io[0, 2],
                     io[1, 2]])


def principal_inertia(phi: F64, mass: float) -> tuple[F64, F64, F64]:
    """Body frame of phi_b (eq. R1) taken with ``mass``: the centre c (3,), the quaternion of
    the principal axes (4,, a proper rotation) and the principal inertias about c (3,)."""
    c = phi[1:4] / mass if mass != 0.0 else np.zeros(3)
    w, v = np.linalg.eigh(inertia_matrix(phi) - mass * skew2(c))
    if np.linalg.det(v) < 0:
        v[:, 0] = -v[:, 0]
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, v.ravel())
    return c, q, w


def set_body_params(m: mujoco.MjModel, b: int, phi: F64) -> None:
    """Write phi_b into the model's body fields (mass, ipos, iquat, diagonal inertia); any
    values, physical or not (``mj_inverse`` is linear in them)."""
    mass = float(phi[0])
    c, q, w = principal_inertia(phi, mass)
    m.body_sameframe[b] = 0  # else MuJoCo ignores ipos/iquat of a body compiled "same frame"
    m.body_mass[b] = mass
    m.body_ipos[b] = c
    m.body_iquat[b] = q
    m.body_inertia[b] = w


def inverse_dynamics(m: mujoco.MjModel, q: F64, qd: F64, qdd: F64) -> F64:
    """MuJoCo's joint torques along (q, qd, qdd), shape (S, n): M qdd + bias + damping qd
    (armature in M), constraints off; plus the model's ``frictionloss`` times sign(qd)
    (smoothed by tanh(qd / :data:`~zrp.gap.dynamics.inertia.V_EPS`)) as the Coulomb friction
    it applies in motion."""
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
    return out + np.asarray(m.dof_frictionloss) * np.tanh(qd / V_EPS)


def gravity_torques(m: mujoco.MjModel, q: F64) -> F64:
    """Gravity's joint torques at ``q``, shape (S, n) (no motion, no friction)."""
    z = np.zeros_like(q)
    fl = np.array(m.dof_frictionloss)
    m.dof_frictionloss[:] = 0.0
    try:
        return inverse_dynamics(m, q, z, z)
    finally:
        m.dof_frictionloss[:] = fl


#: The body fields :func:`set_body_params` writes.
_BODY_FIELDS = ("body_sameframe", "body_mass", "body_ipos", "body_iquat", "body_inertia")


def _steps(phi: F64) -> F64:
    """A step per parameter of the scale of the body (eq. R3 holds for any step)."""
    mass = max(abs(phi[0]), 1e-3)
    inert = max(float(np.abs(phi[4:7]).max()), 1e-6)
    return np.array([0.1 * mass, *(0.01 * mass,) * 3, *(0.1 * inert,) * 6])


def regressor(m: mujoco.MjModel, bodies: Iterable[int], q: F64, qd: F64, qdd: F64
              ) -> tuple[F64, list[tuple[int, str]]]:
    """Y (eq. R2) of ``bodies``, shape (S, n, 10 B), and the (body, parameter) of each
    column."""
    tau0 = inverse_dynamics(m, q, qd, qdd)
    cols, labels = [], []
    for b in bodies:
        phi0 = body_params(m, b)
        # the model's own fields, restored bit for bit (writing phi0 back would round them)
        saved = [np.array(getattr(m, f)[b]) for f in _BODY_FIELDS]
        for j, step in enumerate(_steps(phi0)):
            phi = phi0.copy()
            phi[j] += step
            set_body_params(m, b, phi)
            try:
                cols.append((inverse_dynamics(m, q, qd, qdd) - tau0) / step)
            finally:
                for f, v in zip(_BODY_FIELDS, saved, strict=True):
                    getattr(m, f)[b] = v
            labels.append((b, PARAM_NAMES[j]))
    return np.stack(cols, axis=-1), labels
