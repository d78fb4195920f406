"""Link inertial parameters: their layout, physical feasibility, and the combinations an arm
can show.

Each moving body b has ten standard parameters (eq. R1)::

    phi_b = [m, m c_x, m c_y, m c_z, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz]

(mass, first moments, inertia about the body origin in the body frame). The joint torques are
linear in them, tau = Y(q, qd, qdd) phi + (armature, damping and friction terms) (eq. R2), so
column j of Y is exactly (tau(phi0 + d e_j) - tau(phi0)) / d for any step d (eq. R3): the
arm model's inverse dynamics with one parameter changed (MuJoCo's ``mj_inverse``, in
:mod:`mjcf.inverse`, behind :class:`zrp.gap.dynamics.arm.DynamicArm`). The identifiable
(base) combinations are the right singular vectors of Y stacked over random states with
singular values above ``1e-9`` of the largest (eq. R4): a structural property of the arm,
independent of the log.

Feasibility (eq. R5, Wensing et al. 2017): phi_b is physical iff its pseudo-inertia
J = [[tr(I)/2 1 - I, h], [h^T, m]] is positive definite (positive mass, triangle inequalities
of the principal moments).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from zrp.arrays import F64

if TYPE_CHECKING:
    from zrp.gap.dynamics.arm import DynamicArm

__all__ = ["PARAM_NAMES", "V_EPS", "add_point_mass", "base_directions", "inertia_matrix",
           "pseudo_inertia", "pseudo_inertia_min", "pseudo_inertia_ok", "skew2"]

#: Velocity scale of the smoothed sign function tanh(qd / V_EPS) of Coulomb friction, rad/s.
V_EPS = 0.01

PARAM_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def skew2(c: F64) -> F64:
    """|c|^2 E - c c^T: the parallel-axis term of a unit mass at c, shape (3, 3)."""
    return float(c @ c) * np.eye(3) - np.outer(c, c)


def inertia_matrix(phi: F64) -> F64:
    """The inertia tensor about the body origin of phi_b, shape (3, 3)."""
    return np.array([[phi[4], phi[7], phi[8]], [phi[7], phi[5], phi[9]],
                     [phi[8], phi[9], phi[6]]])


def pseudo_inertia(phi: F64) -> F64:
    """phi_b's pseudo-inertia J = [[tr(I)/2 1 - I, h], [h^T, m]] (eq. R5), shape (4, 4)."""
    i = inertia_matrix(phi)
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


def add_point_mass(phi: F64, mass: float, r: F64) -> F64:
    """phi_b plus a point mass at r (body frame, m) (eq. R1); a negative mass takes one
    away."""
    rr = float(r @ r)
    return phi + mass * np.array([1.0, *r, rr - r[0] ** 2, rr - r[1] ** 2, rr - r[2] ** 2,
                                  -r[0] * r[1], -r[0] * r[2], -r[1] * r[2]])


def base_directions(arm: DynamicArm, n_states: int = 60, seed: int = 0, rtol: float = 1e-9
                    ) -> tuple[F64, F64]:
    """The identifiable directions of the inertial parameters (eq. R4): (V, scale) with V of
    shape (10 B, r) in scaled parameters (phi = phi0 + scale * (V beta))."""
    rng = np.random.default_rng(seed)
    n = arm.n
    lo, hi = _ranges(arm)
    q = rng.uniform(lo, hi, (n_states, n))
    qd = rng.normal(0.0, 1.0, (n_states, n))
    qdd = rng.normal(0.0, 3.0, (n_states, n))
    y, _ = arm.regressor(q, qd, qdd)
    y = y.reshape(-1, y.shape[-1])
    norm = np.linalg.norm(y, axis=0)
    # a parameter that moves no joint torque (to rounding) is left out: 1/norm would be noise
    absent = norm <= 1e-10 * norm.max()
    inv = np.where(absent, 0.0, 1.0 / np.where(absent, 1.0, norm))
    _, s, vt = np.linalg.svd(y * inv, full_matrices=False)
    r = int(np.sum(s > rtol * s[0]))
    return vt[:r].T, inv


def _ranges(arm: DynamicArm) -> tuple[F64, F64]:
    lo, hi = arm.position_limits()
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)
