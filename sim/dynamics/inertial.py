"""Inverse dynamics along a log and its regressor in the link inertial parameters.

Each moving body b has ten standard parameters (eq. R1)::

    phi_b = [m, m c_x, m c_y, m c_z, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz]

(mass, first moments, inertia about the body origin in the body frame). The joint torques are
linear in them, tau = Y(q, qd, qdd) phi + (armature, damping and friction terms) (eq. R2), so
column j of Y is exactly (tau(phi0 + d e_j) - tau(phi0)) / d for any step d (eq. R3): MuJoCo's
``mj_inverse`` on the model with one parameter changed, no finite-difference error. The
identifiable (base) combinations are the right singular vectors of Y stacked over random states
with singular values above ``1e-9`` of the largest (eq. R4): a structural property of the arm,
independent of the log.

Feasibility (eq. R5, Wensing et al. 2017): phi_b is physical iff its pseudo-inertia
J = [[tr(I)/2 1 - I, h], [h^T, m]] is positive definite (positive mass, triangle inequalities
of the principal moments).
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np

from sim.dynamics.arm import Arm
from zrp.arrays import F64

__all__ = ["PARAM_NAMES", "V_EPS", "base_directions", "body_params", "gravity_torques",
           "inverse_dynamics", "pseudo_inertia", "pseudo_inertia_min", "pseudo_inertia_ok",
           "regressor", "set_body_params"]

#: Velocity scale of the smoothed sign function tanh(qd / V_EPS) of Coulomb friction, rad/s.
V_EPS = 0.01

PARAM_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def _skew2(c: F64) -> F64:
    return float(c @ c) * np.eye(3) - np.outer(c, c)


def body_params(m: mujoco.MjModel, b: int) -> F64:
    """phi_b of body ``b`` (eq. R1)."""
    mass = float(m.body_mass[b])
    c = np.array(m.body_ipos[b], dtype=float)
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, m.body_iquat[b])
    r = rot.reshape(3, 3)
    io = r @ np.diag(m.body_inertia[b]) @ r.T + mass * _skew2(c)
    return np.array([mass, *(mass * c), io[0, 0], io[1, 1], io[2, 2], io[0, 1], io[0, 2],
                     io[1, 2]])


def _inertia_matrix(phi: F64) -> F64:
    return np.array([[phi[4], phi[7], phi[8]], [phi[7], phi[5], phi[9]],
                     [phi[8], phi[9], phi[6]]])


def set_body_params(m: mujoco.MjModel, b: int, phi: F64) -> None:
    """Write phi_b into the model's body fields (mass, ipos, iquat, diagonal inertia); any
    values, physical or not (``mj_inverse`` is linear in them)."""
    mass = float(phi[0])
    c = phi[1:4] / mass if mass != 0.0 else np.zeros(3)
    ic = _inertia_matrix(phi) - mass * _skew2(c)
    w, v = np.linalg.eigh(ic)
    if np.linalg.det(v) < 0:
        v[:, 0] = -v[:, 0]
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, v.ravel())
    m.body_sameframe[b] = 0  # else MuJoCo ignores ipos/iquat of a body compiled "same frame"
    m.body_mass[b] = mass
    m.body_ipos[b] = c
    m.body_iquat[b] = q
    m.body_inertia[b] = w


def pseudo_inertia(phi: F64) -> F64:
    """phi_b's pseudo-inertia J = [[tr(I)/2 1 - I, h], [h^T, m]] (eq. R5), shape (4, 4)."""
    i = _inertia_matrix(phi)
    j = np.zeros((4, 4))
    j[:3, :3] = 0.5 * np.trace(i) * np.eye(3) - i
    j[:3, 3] = j[3, :3] = phi[1:4]
    j[3, 3] = phi[0]
    return j


def pseudo_inertia_min(phi: F64) -> float:
    """The smallest eigenvalue of phi_b's pseudo-inertia J (eq. R5)."""
    return float(np.linalg.eigvalsh(pseudo_inertia(phi)).min())


def pseudo_inertia_ok(phi: F64) -> bool:
    """Whether phi_b is physically feasible (eq. R5)."""
    return pseudo_inertia_min(phi) > 0.0


def inverse_dynamics(m: mujoco.MjModel, q: F64, qd: F64, qdd: F64) -> F64:
    """MuJoCo's joint torques along (q, qd, qdd), shape (S, n): M qdd + bias + damping qd
    (armature in M), constraints off; plus the model's ``frictionloss`` times sign(qd)
    (smoothed by tanh(qd / :data:`V_EPS`)) as the Coulomb friction it applies in motion."""
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


def _steps(phi: F64) -> F64:
    """A step per parameter of the scale of the body (eq. R3 holds for any step)."""
    mass = max(abs(phi[0]), 1e-3)
    inert = max(float(np.abs(phi[4:7]).max()), 1e-6)
    return np.array([0.1 * mass, *(0.01 * mass,) * 3, *(0.1 * inert,) * 6])


def regressor(arm: Arm, q: F64, qd: F64, qdd: F64, bodies: Iterable[int] | None = None
              ) -> tuple[F64, list[tuple[int, str]]]:
    """Y (eq. R2), shape (S, n, 10 B), and the (body, parameter) of each column."""
    m = arm.model
    bodies = list(arm.moving_bodies() if bodies is None else bodies)
    tau0 = inverse_dynamics(m, q, qd, qdd)
    cols, labels = [], []
    for b in bodies:
        phi0 = body_params(m, b)
        for j, step in enumerate(_steps(phi0)):
            phi = phi0.copy()
            phi[j] += step
            set_body_params(m, b, phi)
            try:
                cols.append((inverse_dynamics(m, q, qd, qdd) - tau0) / step)
            finally:
                set_body_params(m, b, phi0)
            labels.append((b, PARAM_NAMES[j]))
    return np.stack(cols, axis=-1), labels


def base_directions(arm: Arm, n_states: int = 60, seed: int = 0, rtol: float = 1e-9
                    ) -> tuple[F64, F64]:
    """The identifiable directions of the inertial parameters (eq. R4): (V, scale) with V of
    shape (10 B, r) in scaled parameters (phi = phi0 + scale * (V beta))."""
    rng = np.random.default_rng(seed)
    n = arm.n
    lo, hi = _ranges(arm)
    q = rng.uniform(lo, hi, (n_states, n))
    qd = rng.normal(0.0, 1.0, (n_states, n))
    qdd = rng.normal(0.0, 3.0, (n_states, n))
    y, _ = regressor(arm, q, qd, qdd)
    y = y.reshape(-1, y.shape[-1])
    norm = np.linalg.norm(y, axis=0)
    # a parameter that moves no joint torque (to rounding) is left out: 1/norm would be noise
    absent = norm <= 1e-10 * norm.max()
    inv = np.where(absent, 0.0, 1.0 / np.where(absent, 1.0, norm))
    _, s, vt = np.linalg.svd(y * inv, full_matrices=False)
    r = int(np.sum(s > rtol * s[0]))
    return vt[:r].T, inv


def _ranges(arm: Arm) -> tuple[F64, F64]:
    m = arm.model
    lim = np.array(m.jnt_range, dtype=float)
    limited = np.array(m.jnt_limited, dtype=bool) & (lim[:, 1] > lim[:, 0])
    lo = np.where(limited, lim[:, 0], -np.pi)
    hi = np.where(limited, lim[:, 1], np.pi)
    return lo, hi
