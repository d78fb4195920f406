"""Compiled (numba) kernels behind :mod:`zrp.kinematics` and :mod:`zrp.ik`.

The public functions validate their input and call these; the kernels assume clean,
contiguous float64 arrays. Every kernel is checked in the tests against the vectorised NumPy
implementation of the same equations and against independent references.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Layout of one pose in the kernels: position (3) then Euler-Rodrigues parameters (4).


@njit(cache=True, fastmath=False)
def fk_pose_one(q, axes, bodies, prism, out):
    """Eqs (1)-(6) for one joint vector: writes p and E_{n+1} into out[0:7]."""
    n = axes.shape[0]
    e0 = 1.0
    e1 = 0.0
    e2 = 0.0
    e3 = 0.0
    px = 0.0
    py = 0.0
    pz = 0.0
    for k in range(n + 1):
        bx = bodies[k, 0]
        by = bodies[k, 1]
        bz = bodies[k, 2]
        if bx != 0.0 or by != 0.0 or bz != 0.0:
            # eq (2): b_k = R_{k-1} b_{k,0}, as v + 2 e0 (e x v) + 2 e x (e x v)
            cx = e2 * bz - e3 * by
            cy = e3 * bx - e1 * bz
            cz = e1 * by - e2 * bx
            px += bx + 2.0 * (e0 * cx + e2 * cz - e3 * cy)
            py += by + 2.0 * (e0 * cy + e3 * cx - e1 * cz)
            pz += bz + 2.0 * (e0 * cz + e1 * cy - e2 * cx)
        if k == n:
            break
        ux = axes[k, 0]
        uy = axes[k, 1]
        uz = axes[k, 2]
        if prism[k]:
            cx = e2 * uz - e3 * uy
            cy = e3 * ux - e1 * uz
            cz = e1 * uy - e2 * ux
            d = q[k]
            px += d * (ux + 2.0 * (e0 * cx + e2 * cz - e3 * cy))
            py += d * (uy + 2.0 * (e0 * cy + e3 * cx - e1 * cz))
            pz += d * (uz + 2.0 * (e0 * cz + e1 * cy - e2 * cx))
        else:
            h = 0.5 * q[k]
            s = math.sin(h)
            c = math.cos(h)
            f1 = ux * s
            f2 = uy * s
            f3 = uz * s
            # eqs (4)-(5): E <- E * e_k
            n0 = e0 * c - e1 * f1 - e2 * f2 - e3 * f3
            n1 = e0 * f1 + c * e1 + e2 * f3 - e3 * f2
            n2 = e0 * f2 + c * e2 + e3 * f1 - e1 * f3
            n3 = e0 * f3 + c * e3 + e1 * f2 - e2 * f1
            e0 = n0
            e1 = n1
            e2 = n2
            e3 = n3
    out[0] = px
    out[1] = py
    out[2] = pz
    out[3] = e0
    out[4] = e1
    out[5] = e2
    out[6] = e3


@njit(cache=True)
def fk_pose_batch(q, axes, bodies, prism, out):
    """Batched :func:`fk_pose_one`: q (N, n) -> out (N, 7)."""
    for i in range(q.shape[0]):
        fk_pose_one(q[i], axes, bodies, prism, out[i])


@njit(cache=True)
def fk_jac_one(q, axes, bodies, prism, pose, jac):
    """Pose (7,) and the eq (7) Jacobian [omega_h; V_p] (6, n) of one joint vector."""
    n = axes.shape[0]
    e0 = 1.0
    e1 = 0.0
    e2 = 0.0
    e3 = 0.0
    px = 0.0
    py = 0.0
    pz = 0.0
    # First pass stores current axes (rows 0-2) and joint points (rows 3-5, temporarily).
    for k in range(n + 1):
        bx = bodies[k, 0]
        by = bodies[k, 1]
        bz = bodies[k, 2]
        cx = e2 * bz - e3 * by
        cy = e3 * bx - e1 * bz
        cz = e1 * by - e2 * bx
        px += bx + 2.0 * (e0 * cx + e2 * cz - e3 * cy)
        py += by + 2.0 * (e0 * cy + e3 * cx - e1 * cz)
        pz += bz + 2.0 * (e0 * cz + e1 * cy - e2 * cx)
        if k == n:
            break
        ux = axes[k, 0]
        uy = axes[k, 1]
        uz = axes[k, 2]
        cx = e2 * uz - e3 * uy
        cy = e3 * ux - e1 * uz
        cz = e1 * uy - e2 * ux
        wx = ux + 2.0 * (e0 * cx + e2 * cz - e3 * cy)
        wy = uy + 2.0 * (e0 * cy + e3 * cx - e1 * cz)
        wz = uz + 2.0 * (e0 * cz + e1 * cy - e2 * cx)
        jac[0, k] = wx
        jac[1, k] = wy
        jac[2, k] = wz
        jac[3, k] = px
        jac[4, k] = py
        jac[5, k] = pz
        if prism[k]:
            d = q[k]
            px += d * wx
            py += d * wy
            pz += d * wz
        else:
            h = 0.5 * q[k]
            s = math.sin(h)
            c = math.cos(h)
            f1 = ux * s
            f2 = uy * s
            f3 = uz * s
            n0 = e0 * c - e1 * f1 - e2 * f2 - e3 * f3
            n1 = e0 * f1 + c * e1 + e2 * f3 - e3 * f2
            n2 = e0 * f2 + c * e2 + e3 * f1 - e1 * f3
            n3 = e0 * f3 + c * e3 + e1 * f2 - e2 * f1
            e0 = n0
            e1 = n1
            e2 = n2
            e3 = n3
    pose[0] = px
    pose[1] = py
    pose[2] = pz
    pose[3] = e0
    pose[4] = e1
    pose[5] = e2
    pose[6] = e3
    for k in range(n):
        wx = jac[0, k]
        wy = jac[1, k]
        wz = jac[2, k]
        if prism[k]:
            jac[0, k] = 0.0
            jac[1, k] = 0.0
            jac[2, k] = 0.0
            jac[3, k] = wx
            jac[4, k] = wy
            jac[5, k] = wz
        else:
            rx = px - jac[3, k]
            ry = py - jac[4, k]
            rz = pz - jac[5, k]
            jac[3, k] = wy * rz - wz * ry
            jac[4, k] = wz * rx - wx * rz
            jac[5, k] = wx * ry - wy * rx


@njit(cache=True)
def jac_batch(q, axes, bodies, prism, pose, jac):
    """Batched :func:`fk_jac_one`: q (N, n) -> pose (N, 7), jac (N, 6, n)."""
    for i in range(q.shape[0]):
        fk_jac_one(q[i], axes, bodies, prism, pose[i], jac[i])


def kernel_arrays(axes: np.ndarray, bodies: np.ndarray, prism: np.ndarray) -> tuple:
    """Contiguous copies of a model's arrays in the kernels' layout."""
    return (np.ascontiguousarray(axes, dtype=np.float64),
            np.ascontiguousarray(bodies, dtype=np.float64),
            np.ascontiguousarray(prism, dtype=np.bool_))
