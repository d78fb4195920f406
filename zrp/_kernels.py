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


# ---- sin and cos that vectorise --------------------------------------------------------------
# libm's sin/cos cost ~16 ns each and stop LLVM from vectorising the loops over poses. This is
# the fdlibm algorithm (Cody-Waite reduction by pi/2 in three parts, degree-13/14 minimax
# polynomials on [-pi/4, pi/4]) written branch-free; it is within 1 ulp of libm for the joint
# angles met in practice (|x| < 1e5 rad), which the tests check.
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624879595063154e-21
_TWO_OVER_PI = 6.36619772367581382433e-01
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
_FM = {"contract"}  # allow fused multiply-add only; no reassociation (keeps the reduction exact)
_BLOCK = 256


@njit(inline="always", fastmath=_FM)
def sincos(x):
    """(sin x, cos x) without branches."""
    k = math.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    c = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    ki = np.int64(k) & 3
    ss = c if (ki & 1) else s
    cc = s if (ki & 1) else c
    ss = -ss if (ki & 2) else ss
    cc = -cc if ((ki + 1) & 2) else cc
    return ss, cc


@njit(cache=True)
def all_finite(x):
    """True when every element of the contiguous array ``x`` is finite (stops at the first)."""
    flat = x.ravel()
    for i in range(flat.size):
        if not math.isfinite(flat[i]):
            return False
    return True


@njit(cache=True)
def sincos_batch(x, s, c):
    """Vectorised :func:`sincos` over arrays of shape (m,) (for tests)."""
    for i in range(x.size):
        s[i], c[i] = sincos(x[i])


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
            s, c = sincos(0.5 * q[k])
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


@njit(cache=True, fastmath=_FM)
def fk_pose_batch(q, axes, bodies, prism, out):
    """Batched :func:`fk_pose_one`: q (N, n) -> out (N, 7).

    Works on blocks of poses held as structure-of-arrays so that every inner loop runs over
    poses with no branches and vectorises (SIMD); the arithmetic is that of fk_pose_one.
    """
    N = q.shape[0]
    n = axes.shape[0]
    e0 = np.empty(_BLOCK)
    e1 = np.empty(_BLOCK)
    e2 = np.empty(_BLOCK)
    e3 = np.empty(_BLOCK)
    px = np.empty(_BLOCK)
    py = np.empty(_BLOCK)
    pz = np.empty(_BLOCK)
    qb = np.empty(_BLOCK)
    for start in range(0, N, _BLOCK):
        m = min(_BLOCK, N - start)
        for i in range(m):
            e0[i] = 1.0
            e1[i] = 0.0
            e2[i] = 0.0
            e3[i] = 0.0
            px[i] = 0.0
            py[i] = 0.0
            pz[i] = 0.0
        for k in range(n + 1):
            bx = bodies[k, 0]
            by = bodies[k, 1]
            bz = bodies[k, 2]
            if bx != 0.0 or by != 0.0 or bz != 0.0:
                for i in range(m):
                    a0 = e0[i]
                    a1 = e1[i]
                    a2 = e2[i]
                    a3 = e3[i]
                    cx = a2 * bz - a3 * by
                    cy = a3 * bx - a1 * bz
                    cz = a1 * by - a2 * bx
                    px[i] += bx + 2.0 * (a0 * cx + a2 * cz - a3 * cy)
                    py[i] += by + 2.0 * (a0 * cy + a3 * cx - a1 * cz)
                    pz[i] += bz + 2.0 * (a0 * cz + a1 * cy - a2 * cx)
            if k == n:
                break
            for i in range(m):
                qb[i] = q[start + i, k]
            ux = axes[k, 0]
            uy = axes[k, 1]
            uz = axes[k, 2]
            if prism[k]:
                for i in range(m):
                    a0 = e0[i]
                    a1 = e1[i]
                    a2 = e2[i]
                    a3 = e3[i]
                    cx = a2 * uz - a3 * uy
                    cy = a3 * ux - a1 * uz
                    cz = a1 * uy - a2 * ux
                    d = qb[i]
                    px[i] += d * (ux + 2.0 * (a0 * cx + a2 * cz - a3 * cy))
                    py[i] += d * (uy + 2.0 * (a0 * cy + a3 * cx - a1 * cz))
                    pz[i] += d * (uz + 2.0 * (a0 * cz + a1 * cy - a2 * cx))
            else:
                for i in range(m):
                    s, c = sincos(0.5 * qb[i])
                    f1 = ux * s
                    f2 = uy * s
                    f3 = uz * s
                    a0 = e0[i]
                    a1 = e1[i]
                    a2 = e2[i]
                    a3 = e3[i]
                    e0[i] = a0 * c - a1 * f1 - a2 * f2 - a3 * f3
                    e1[i] = a0 * f1 + c * a1 + a2 * f3 - a3 * f2
                    e2[i] = a0 * f2 + c * a2 + a3 * f1 - a1 * f3
                    e3[i] = a0 * f3 + c * a3 + a1 * f2 - a2 * f1
        for i in range(m):
            j = start + i
            out[j, 0] = px[i]
            out[j, 1] = py[i]
            out[j, 2] = pz[i]
            out[j, 3] = e0[i]
            out[j, 4] = e1[i]
            out[j, 5] = e2[i]
            out[j, 6] = e3[i]


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
            s, c = sincos(0.5 * q[k])
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


@njit(cache=True, fastmath=_FM)
def jac_batch(q, axes, bodies, prism, pose, jac):
    """Batched :func:`fk_jac_one`: q (N, n) -> pose (N, 7) (or shape (0, 7) to skip), jac
    (N, 6, n).

    Blocked structure-of-arrays like :func:`fk_pose_batch`, so the loops over poses vectorise.
    """
    N = q.shape[0]
    n = axes.shape[0]
    e0 = np.empty(_BLOCK)
    e1 = np.empty(_BLOCK)
    e2 = np.empty(_BLOCK)
    e3 = np.empty(_BLOCK)
    px = np.empty(_BLOCK)
    py = np.empty(_BLOCK)
    pz = np.empty(_BLOCK)
    qb = np.empty(_BLOCK)
    w = np.empty((n, 3, _BLOCK))
    o = np.empty((n, 3, _BLOCK))
    for start in range(0, N, _BLOCK):
        m = min(_BLOCK, N - start)
        for i in range(m):
            e0[i] = 1.0
            e1[i] = 0.0
            e2[i] = 0.0
            e3[i] = 0.0
            px[i] = 0.0
            py[i] = 0.0
            pz[i] = 0.0
        for k in range(n + 1):
            bx = bodies[k, 0]
            by = bodies[k, 1]
            bz = bodies[k, 2]
            for i in range(m):
                a0 = e0[i]
                a1 = e1[i]
                a2 = e2[i]
                a3 = e3[i]
                cx = a2 * bz - a3 * by
                cy = a3 * bx - a1 * bz
                cz = a1 * by - a2 * bx
                px[i] += bx + 2.0 * (a0 * cx + a2 * cz - a3 * cy)
                py[i] += by + 2.0 * (a0 * cy + a3 * cx - a1 * cz)
                pz[i] += bz + 2.0 * (a0 * cz + a1 * cy - a2 * cx)
            if k == n:
                break
            ux = axes[k, 0]
            uy = axes[k, 1]
            uz = axes[k, 2]
            for i in range(m):
                qb[i] = q[start + i, k]
                a0 = e0[i]
                a1 = e1[i]
                a2 = e2[i]
                a3 = e3[i]
                cx = a2 * uz - a3 * uy
                cy = a3 * ux - a1 * uz
                cz = a1 * uy - a2 * ux
                w[k, 0, i] = ux + 2.0 * (a0 * cx + a2 * cz - a3 * cy)
                w[k, 1, i] = uy + 2.0 * (a0 * cy + a3 * cx - a1 * cz)
                w[k, 2, i] = uz + 2.0 * (a0 * cz + a1 * cy - a2 * cx)
                o[k, 0, i] = px[i]
                o[k, 1, i] = py[i]
                o[k, 2, i] = pz[i]
            if prism[k]:
                for i in range(m):
                    d = qb[i]
                    px[i] += d * w[k, 0, i]
                    py[i] += d * w[k, 1, i]
                    pz[i] += d * w[k, 2, i]
            else:
                for i in range(m):
                    s, c = sincos(0.5 * qb[i])
                    f1 = ux * s
                    f2 = uy * s
                    f3 = uz * s
                    a0 = e0[i]
                    a1 = e1[i]
                    a2 = e2[i]
                    a3 = e3[i]
                    e0[i] = a0 * c - a1 * f1 - a2 * f2 - a3 * f3
                    e1[i] = a0 * f1 + c * a1 + a2 * f3 - a3 * f2
                    e2[i] = a0 * f2 + c * a2 + a3 * f1 - a1 * f3
                    e3[i] = a0 * f3 + c * a3 + a1 * f2 - a2 * f1
        if pose.shape[0] == N:  # the caller may pass an empty array to skip the poses
            for i in range(m):
                j = start + i
                pose[j, 0] = px[i]
                pose[j, 1] = py[i]
                pose[j, 2] = pz[i]
                pose[j, 3] = e0[i]
                pose[j, 4] = e1[i]
                pose[j, 5] = e2[i]
                pose[j, 6] = e3[i]
        for k in range(n):
            if prism[k]:
                for i in range(m):
                    j = start + i
                    jac[j, 0, k] = 0.0
                    jac[j, 1, k] = 0.0
                    jac[j, 2, k] = 0.0
                    jac[j, 3, k] = w[k, 0, i]
                    jac[j, 4, k] = w[k, 1, i]
                    jac[j, 5, k] = w[k, 2, i]
            else:
                for i in range(m):
                    j = start + i
                    wx = w[k, 0, i]
                    wy = w[k, 1, i]
                    wz = w[k, 2, i]
                    rx = px[i] - o[k, 0, i]
                    ry = py[i] - o[k, 1, i]
                    rz = pz[i] - o[k, 2, i]
                    jac[j, 0, k] = wx
                    jac[j, 1, k] = wy
                    jac[j, 2, k] = wz
                    jac[j, 3, k] = wy * rz - wz * ry
                    jac[j, 4, k] = wz * rx - wx * rz
                    jac[j, 5, k] = wx * ry - wy * rx


def kernel_arrays(axes: np.ndarray, bodies: np.ndarray, prism: np.ndarray) -> tuple:
    """Contiguous copies of a model's arrays in the kernels' layout."""
    return (np.ascontiguousarray(axes, dtype=np.float64),
            np.ascontiguousarray(bodies, dtype=np.float64),
            np.ascontiguousarray(prism, dtype=np.bool_))
