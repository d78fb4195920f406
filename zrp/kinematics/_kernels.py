"""Compiled (numba) kernels behind :mod:`zrp.kinematics.forward` and :mod:`zrp.kinematics.ik`.

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


@njit(inline="always", fastmath=_FM)
def rotate(e0, e1, e2, e3, x, y, z):
    """Eq (2): the vector (x, y, z) rotated by unit parameters (e0, e1, e2, e3), written as
    v + 2 e0 (e x v) + 2 e x (e x v)."""
    cx = e2 * z - e3 * y
    cy = e3 * x - e1 * z
    cz = e1 * y - e2 * x
    return (x + 2.0 * (e0 * cx + e2 * cz - e3 * cy),
            y + 2.0 * (e0 * cy + e3 * cx - e1 * cz),
            z + 2.0 * (e0 * cz + e1 * cy - e2 * cx))


@njit(inline="always", fastmath=_FM)
def turn(e0, e1, e2, e3, ux, uy, uz, q):
    """Eqs (4)-(6): E * e(u, q), the composition with a turn by q (rad) about the unit u."""
    s, c = sincos(0.5 * q)
    f1 = ux * s
    f2 = uy * s
    f3 = uz * s
    return (e0 * c - e1 * f1 - e2 * f2 - e3 * f3,
            e0 * f1 + c * e1 + e2 * f3 - e3 * f2,
            e0 * f2 + c * e2 + e3 * f1 - e1 * f3,
            e0 * f3 + c * e3 + e1 * f2 - e2 * f1)


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
    e0, e1, e2, e3 = 1.0, 0.0, 0.0, 0.0
    px, py, pz = 0.0, 0.0, 0.0
    for k in range(n + 1):
        bx, by, bz = rotate(e0, e1, e2, e3, bodies[k, 0], bodies[k, 1], bodies[k, 2])
        px += bx
        py += by
        pz += bz
        if k == n:
            break
        if prism[k]:
            wx, wy, wz = rotate(e0, e1, e2, e3, axes[k, 0], axes[k, 1], axes[k, 2])
            px += q[k] * wx
            py += q[k] * wy
            pz += q[k] * wz
        else:
            e0, e1, e2, e3 = turn(e0, e1, e2, e3, axes[k, 0], axes[k, 1], axes[k, 2], q[k])
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
    qb = np.empty(_BLOCK)  # joint k's values, contiguous (a strided read stops SIMD)
    for start in range(0, N, _BLOCK):
        m = min(_BLOCK, N - start)
        e0[:m] = 1.0
        e1[:m] = 0.0
        e2[:m] = 0.0
        e3[:m] = 0.0
        px[:m] = 0.0
        py[:m] = 0.0
        pz[:m] = 0.0
        for k in range(n + 1):
            bx = bodies[k, 0]
            by = bodies[k, 1]
            bz = bodies[k, 2]
            if bx != 0.0 or by != 0.0 or bz != 0.0:  # zero body vectors (wrists) cost nothing
                for i in range(m):
                    x, y, z = rotate(e0[i], e1[i], e2[i], e3[i], bx, by, bz)
                    px[i] += x
                    py[i] += y
                    pz[i] += z
            if k == n:
                break
            ux = axes[k, 0]
            uy = axes[k, 1]
            uz = axes[k, 2]
            for i in range(m):
                qb[i] = q[start + i, k]
            if prism[k]:
                for i in range(m):
                    d = qb[i]
                    x, y, z = rotate(e0[i], e1[i], e2[i], e3[i], ux, uy, uz)
                    px[i] += d * x
                    py[i] += d * y
                    pz[i] += d * z
            else:
                for i in range(m):
                    e0[i], e1[i], e2[i], e3[i] = turn(e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                      qb[i])
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
    e0, e1, e2, e3 = 1.0, 0.0, 0.0, 0.0
    px, py, pz = 0.0, 0.0, 0.0
    # First pass stores current axes (rows 0-2) and joint points (rows 3-5, temporarily).
    for k in range(n + 1):
        bx, by, bz = rotate(e0, e1, e2, e3, bodies[k, 0], bodies[k, 1], bodies[k, 2])
        px += bx
        py += by
        pz += bz
        if k == n:
            break
        wx, wy, wz = rotate(e0, e1, e2, e3, axes[k, 0], axes[k, 1], axes[k, 2])
        jac[0, k] = wx
        jac[1, k] = wy
        jac[2, k] = wz
        jac[3, k] = px
        jac[4, k] = py
        jac[5, k] = pz
        if prism[k]:
            px += q[k] * wx
            py += q[k] * wy
            pz += q[k] * wz
        else:
            e0, e1, e2, e3 = turn(e0, e1, e2, e3, axes[k, 0], axes[k, 1], axes[k, 2], q[k])
    pose[0] = px
    pose[1] = py
    pose[2] = pz
    pose[3] = e0
    pose[4] = e1
    pose[5] = e2
    pose[6] = e3
    for k in range(n):
        _jac_column(prism[k], jac[0, k], jac[1, k], jac[2, k], px - jac[3, k], py - jac[4, k],
                    pz - jac[5, k], jac[:, k])


@njit(inline="always", fastmath=_FM)
def _jac_column(prismatic, wx, wy, wz, rx, ry, rz, col):
    """Eq (7) column from the current axis w and r = p - p_k: [w; w x r] or [0; w]."""
    if prismatic:
        col[0] = 0.0
        col[1] = 0.0
        col[2] = 0.0
        col[3] = wx
        col[4] = wy
        col[5] = wz
    else:
        col[0] = wx
        col[1] = wy
        col[2] = wz
        col[3] = wy * rz - wz * ry
        col[4] = wz * rx - wx * rz
        col[5] = wx * ry - wy * rx


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
    w = np.empty((n, 3, _BLOCK))  # current axes u_k
    o = np.empty((n, 3, _BLOCK))  # current joint points p_k
    qb = np.empty(_BLOCK)  # joint k's values, contiguous (a strided read stops SIMD)
    for start in range(0, N, _BLOCK):
        m = min(_BLOCK, N - start)
        e0[:m] = 1.0
        e1[:m] = 0.0
        e2[:m] = 0.0
        e3[:m] = 0.0
        px[:m] = 0.0
        py[:m] = 0.0
        pz[:m] = 0.0
        for k in range(n + 1):
            bx = bodies[k, 0]
            by = bodies[k, 1]
            bz = bodies[k, 2]
            for i in range(m):
                x, y, z = rotate(e0[i], e1[i], e2[i], e3[i], bx, by, bz)
                px[i] += x
                py[i] += y
                pz[i] += z
            if k == n:
                break
            ux = axes[k, 0]
            uy = axes[k, 1]
            uz = axes[k, 2]
            for i in range(m):
                qb[i] = q[start + i, k]
            for i in range(m):
                w[k, 0, i], w[k, 1, i], w[k, 2, i] = rotate(e0[i], e1[i], e2[i], e3[i], ux, uy,
                                                            uz)
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
                    e0[i], e1[i], e2[i], e3[i] = turn(e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                      qb[i])
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
            pk = prism[k]
            for i in range(m):
                _jac_column(pk, w[k, 0, i], w[k, 1, i], w[k, 2, i], px[i] - o[k, 0, i],
                            py[i] - o[k, 1, i], pz[i] - o[k, 2, i], jac[start + i, :, k])


def kernel_arrays(axes: np.ndarray, bodies: np.ndarray, prism: np.ndarray) -> tuple:
    """Contiguous copies of a model's arrays in the kernels' layout."""
    return (np.ascontiguousarray(axes, dtype=np.float64),
            np.ascontiguousarray(bodies, dtype=np.float64),
            np.ascontiguousarray(prism, dtype=np.bool_))
