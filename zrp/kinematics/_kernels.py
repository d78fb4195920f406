"""Compiled (numba) kernels behind :mod:`zrp.kinematics.forward` and :mod:`zrp.kinematics.ik`.

The public functions validate their input and call these; the kernels assume clean,
contiguous float64 arrays. Every kernel is checked in the tests against the vectorised NumPy
implementation of the same equations and against independent references.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

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
_STREAM_MIN = 32768  # poses (1.8 MB of output): from here on fk_pose_batch streams its stores


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


@njit(inline="always", fastmath=_FM)
def rotate_code(code, e0, e1, e2, e3, x, y, z):
    """:func:`rotate` with the zero components of (x, y, z) left out: ``code`` 0 for the zero
    vector, 1/2/3 when only x/y/z is nonzero, 4 otherwise (:func:`_code`)."""
    if code == 1:
        cy = e3 * x
        cz = -e2 * x
        return (x + 2.0 * (e2 * cz - e3 * cy), 2.0 * (e0 * cy - e1 * cz),
                2.0 * (e0 * cz + e1 * cy))
    if code == 2:
        cx = -e3 * y
        cz = e1 * y
        return (2.0 * (e0 * cx + e2 * cz), y + 2.0 * (e3 * cx - e1 * cz),
                2.0 * (e0 * cz - e2 * cx))
    if code == 3:
        cx = e2 * z
        cy = -e1 * z
        return (2.0 * (e0 * cx - e3 * cy), 2.0 * (e0 * cy + e3 * cx),
                z + 2.0 * (e1 * cy - e2 * cx))
    if code == 0:
        return 0.0, 0.0, 0.0
    return rotate(e0, e1, e2, e3, x, y, z)


@njit(inline="always", fastmath=_FM)
def turn_code(code, e0, e1, e2, e3, ux, uy, uz, q):
    """:func:`turn` about a coordinate axis (``code`` 1/2/3) with 8 multiplications instead
    of 16; the general turn otherwise."""
    s, c = sincos(0.5 * q)
    if code == 1:
        f = ux * s
        return e0 * c - e1 * f, e0 * f + c * e1, c * e2 + e3 * f, c * e3 - e2 * f
    if code == 2:
        f = uy * s
        return e0 * c - e2 * f, c * e1 - e3 * f, e0 * f + c * e2, c * e3 + e1 * f
    if code == 3:
        f = uz * s
        return e0 * c - e3 * f, c * e1 + e2 * f, c * e2 - e1 * f, e0 * f + c * e3
    f1 = ux * s
    f2 = uy * s
    f3 = uz * s
    return (e0 * c - e1 * f1 - e2 * f2 - e3 * f3,
            e0 * f1 + c * e1 + e2 * f3 - e3 * f2,
            e0 * f2 + c * e2 + e3 * f1 - e1 * f3,
            e0 * f3 + c * e3 + e1 * f2 - e2 * f1)


# The block loops below are written once per code (the code is fixed for the whole loop, so
# each loop is branch-free and vectorises); they call the same inline arithmetic as the
# single-pose kernels, which therefore give the very same bits.
@njit(fastmath=_FM)
def _body_block(e0, e1, e2, e3, px, py, pz, m, code, bx, by, bz):
    """p += R(E) b over a block (eq 2), with the loop chosen by b's sparsity ``code``."""
    if code == 1:
        for i in range(m):
            x, y, z = rotate_code(1, e0[i], e1[i], e2[i], e3[i], bx, by, bz)
            px[i] += x
            py[i] += y
            pz[i] += z
    elif code == 2:
        for i in range(m):
            x, y, z = rotate_code(2, e0[i], e1[i], e2[i], e3[i], bx, by, bz)
            px[i] += x
            py[i] += y
            pz[i] += z
    elif code == 3:
        for i in range(m):
            x, y, z = rotate_code(3, e0[i], e1[i], e2[i], e3[i], bx, by, bz)
            px[i] += x
            py[i] += y
            pz[i] += z
    elif code == 4:
        for i in range(m):
            x, y, z = rotate(e0[i], e1[i], e2[i], e3[i], bx, by, bz)
            px[i] += x
            py[i] += y
            pz[i] += z


@njit(fastmath=_FM)
def _turn_block(e0, e1, e2, e3, qb, m, code, ux, uy, uz):
    """E <- E * e(u, q) over a block (eqs 4-6), with the loop chosen by u's ``code``."""
    if code == 1:
        for i in range(m):
            e0[i], e1[i], e2[i], e3[i] = turn_code(1, e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                   qb[i])
    elif code == 2:
        for i in range(m):
            e0[i], e1[i], e2[i], e3[i] = turn_code(2, e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                   qb[i])
    elif code == 3:
        for i in range(m):
            e0[i], e1[i], e2[i], e3[i] = turn_code(3, e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                   qb[i])
    else:
        for i in range(m):
            e0[i], e1[i], e2[i], e3[i] = turn_code(4, e0[i], e1[i], e2[i], e3[i], ux, uy, uz,
                                                   qb[i])


# ---- streamed (non-temporal) stores -----------------------------------------------------------
# A batch of 1e6 poses writes 56 MB that the kernel never reads back: an ordinary store first
# reads each cache line from memory (read-for-ownership), i.e. 112 B of traffic a pose instead
# of 56. A non-temporal store writes whole lines through the write-combining buffers without
# that read (tests/benchmarks/bench_speed.py: ~1.14x the kernel's rate). LLVM's
# ``!nontemporal`` hint; on targets without such stores it is an ordinary store.
@intrinsic
def store_stream(typingctx, arr, idx, val):
    """``arr[idx] = val`` (1-D C-contiguous float64 ``arr``) as a non-temporal store; the
    caller ends with :func:`store_fence`."""
    if not (isinstance(arr, types.Array) and arr.ndim == 1 and arr.layout == "C"
            and arr.dtype == types.float64):
        return None
    sig = types.void(arr, types.intp, types.float64)

    def codegen(context, builder, signature, args):
        a, i, v = args
        data = context.make_array(signature.args[0])(context, builder, a).data
        st = builder.store(v, builder.gep(data, [i]))
        st.set_metadata("nontemporal", builder.module.add_metadata([cgutils.int32_t(1)]))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def store_fence(typingctx):
    """A full memory fence: the streamed stores are visible to every thread after it (they
    are weakly ordered)."""
    sig = types.void()

    def codegen(context, builder, signature, args):
        builder.fence("seq_cst")
        return context.get_dummy_value()

    return sig, codegen


@njit(cache=True, fastmath=_FM, nogil=True)  # nogil: zrp.kinematics.parallel
def fk_pose_batch(q, axes, bodies, prism, lim, out):
    """Batched :func:`fk_pose_one`: q (N, n) -> out (N, 7) (C-contiguous); returns True when every
    |q[:, k]| <= lim[k] (finite), False otherwise (out is then not to be used).

    The range check rides on the copy of each joint's values into the block (no separate
    pass over q, no early exit: it vectorises).

    Works on blocks of poses held as structure-of-arrays so that every inner loop runs over
    poses with no branches and vectorises (SIMD); the arithmetic is that of fk_pose_one, with
    the zero components of coordinate-axis joint axes and body vectors left out
    (:func:`_code`: a turn about a coordinate axis costs 8 multiplications instead of 16, a
    body vector along one axis is rotated with 9 instead of 18).
    """
    N = q.shape[0]
    n = axes.shape[0]
    acode = np.empty(n, np.int64)
    bcode = np.empty(n + 1, np.int64)
    for k in range(n + 1):
        bcode[k] = _code(bodies[k, 0], bodies[k, 1], bodies[k, 2])
        if k < n:
            acode[k] = _code(axes[k, 0], axes[k, 1], axes[k, 2])
    e0 = np.empty(_BLOCK)
    e1 = np.empty(_BLOCK)
    e2 = np.empty(_BLOCK)
    e3 = np.empty(_BLOCK)
    px = np.empty(_BLOCK)
    py = np.empty(_BLOCK)
    pz = np.empty(_BLOCK)
    qb = np.empty(_BLOCK)  # joint k's values, contiguous (a strided read stops SIMD)
    flat = out.reshape(-1)  # out is C-contiguous (N, 7)
    # streamed stores only when out outgrows the caches (a small out is read back at once
    # by the caller, from the cache when written the ordinary way)
    stream = N >= _STREAM_MIN
    bad = 0
    for start in range(0, N, _BLOCK):
        m = min(_BLOCK, N - start)
        e0[:m] = 1.0
        e1[:m] = 0.0
        e2[:m] = 0.0
        e3[:m] = 0.0
        px[:m] = bodies[0, 0]  # R_0 = I: b_1 needs no rotation
        py[:m] = bodies[0, 1]
        pz[:m] = bodies[0, 2]
        for k in range(n):
            if k > 0:
                _body_block(e0, e1, e2, e3, px, py, pz, m, bcode[k], bodies[k, 0],
                            bodies[k, 1], bodies[k, 2])
            bad += _load_block(q, start, m, k, lim[k], qb)
            if prism[k]:
                for i in range(m):
                    d = qb[i]
                    x, y, z = rotate(e0[i], e1[i], e2[i], e3[i], axes[k, 0], axes[k, 1],
                                     axes[k, 2])
                    px[i] += d * x
                    py[i] += d * y
                    pz[i] += d * z
            else:
                _turn_block(e0, e1, e2, e3, qb, m, acode[k], axes[k, 0], axes[k, 1],
                            axes[k, 2])
        _body_block(e0, e1, e2, e3, px, py, pz, m, bcode[n], bodies[n, 0], bodies[n, 1],
                    bodies[n, 2])
        if stream:  # out is written once and not read here
            for i in range(m):
                j = 7 * (start + i)
                store_stream(flat, j, px[i])
                store_stream(flat, j + 1, py[i])
                store_stream(flat, j + 2, pz[i])
                store_stream(flat, j + 3, e0[i])
                store_stream(flat, j + 4, e1[i])
                store_stream(flat, j + 5, e2[i])
                store_stream(flat, j + 6, e3[i])
        else:
            for i in range(m):
                j = 7 * (start + i)
                flat[j] = px[i]
                flat[j + 1] = py[i]
                flat[j + 2] = pz[i]
                flat[j + 3] = e0[i]
                flat[j + 4] = e1[i]
                flat[j + 5] = e2[i]
                flat[j + 6] = e3[i]
    if stream:
        store_fence()
    return bad == 0


@njit(inline="always")
def _load_block(q, start, m, k, limk, qb):
    """qb[:m] = q[start:start + m, k]; returns how many are not within |x| <= limk (NaN is
    not)."""
    for i in range(m):
        qb[i] = q[start + i, k]
    bad = 0
    for i in range(m):  # contiguous now: a vectorised count
        bad += not abs(qb[i]) <= limk
    return bad


@njit(inline="always")
def _code(x, y, z):
    """0 for the zero vector, 1/2/3 when only x/y/z is nonzero, 4 otherwise."""
    nz = (x != 0.0) + (y != 0.0) + (z != 0.0)
    if nz == 0:
        return 0
    if nz > 1:
        return 4
    return 1 if x != 0.0 else (2 if y != 0.0 else 3)


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


@njit(cache=True, fastmath=_FM, nogil=True)  # nogil: zrp.kinematics.parallel
def jac_batch(q, axes, bodies, prism, lim, pose, jac):
    """Batched :func:`fk_jac_one`: q (N, n) -> pose (N, 7) (or shape (0, 7) to skip), jac
    (N, 6, n); returns True when every |q[:, k]| <= lim[k] (as :func:`fk_pose_batch`).

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
    acode = np.empty(n, np.int64)
    bcode = np.empty(n + 1, np.int64)
    for k in range(n + 1):
        bcode[k] = _code(bodies[k, 0], bodies[k, 1], bodies[k, 2])
        if k < n:
            acode[k] = _code(axes[k, 0], axes[k, 1], axes[k, 2])
    w = np.empty((n, 3, _BLOCK))  # current axes u_k
    o = np.empty((n, 3, _BLOCK))  # current joint points p_k
    qb = np.empty(_BLOCK)  # joint k's values, contiguous (a strided read stops SIMD)
    bad = 0
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
            _body_block(e0, e1, e2, e3, px, py, pz, m, bcode[k], bodies[k, 0], bodies[k, 1],
                        bodies[k, 2])
            if k == n:
                break
            ux = axes[k, 0]
            uy = axes[k, 1]
            uz = axes[k, 2]
            bad += _load_block(q, start, m, k, lim[k], qb)
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
                _turn_block(e0, e1, e2, e3, qb, m, acode[k], ux, uy, uz)
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
    return bad == 0


# ---- one pose from Python: one packed model array ---------------------------------------------
# Numba's dispatcher unboxes each array argument (~0.1-0.25 us apiece); a single call passes
# q, the packed model and the output only. Packed layout (1-D float64): axes u_{k,0} (3n),
# bodies b_{k,0} (3(n + 1)), then the prismatic flags as 0/1 (n).


@njit(inline="always")
def _packed_q_ok(q, n):
    """True when q is contiguous and every |q[k]| <= 1e6 (the revolute range of
    _range_kernels; non-finite values fail): otherwise the packed kernels decline and the
    general path names the joint. Contiguity is checked here, not by the caller: the one-pose
    paths call the kernels' bare entry points (forward._entry), which take any 1-D float64
    array as a contiguous one."""
    if n > 1 and q.strides[0] != q.itemsize:
        return False
    for k in range(n):
        if not abs(q[k]) <= 1e6:
            return False
    return True


@njit(cache=True, fastmath=_FM)
def fk_pose_packed(q, packed, p, er):
    """:func:`fk_pose_one` on the packed model into the position ``p`` (3) and the
    Euler-Rodrigues parameters ``er`` (4): two arrays, which the caller returns as they are
    (two fresh arrays cost less than one and two views of it); returns False (p and er
    untouched) when q has a non-finite value, |q| > 1e6 or not the model's n values."""
    n = (packed.shape[0] - 3) // 7
    if q.shape[0] != n or not _packed_q_ok(q, n):
        return False
    nb = 3 * n
    npr = nb + 3 * (n + 1)
    e0, e1, e2, e3 = 1.0, 0.0, 0.0, 0.0
    px, py, pz = 0.0, 0.0, 0.0
    for k in range(n + 1):
        b = nb + 3 * k
        bx, by, bz = rotate_code(_code(packed[b], packed[b + 1], packed[b + 2]), e0, e1, e2,
                                 e3, packed[b], packed[b + 1], packed[b + 2])
        px += bx
        py += by
        pz += bz
        if k == n:
            break
        a = 3 * k
        if packed[npr + k] != 0.0:
            wx, wy, wz = rotate(e0, e1, e2, e3, packed[a], packed[a + 1], packed[a + 2])
            px += q[k] * wx
            py += q[k] * wy
            pz += q[k] * wz
        else:
            e0, e1, e2, e3 = turn_code(_code(packed[a], packed[a + 1], packed[a + 2]), e0, e1,
                                       e2, e3, packed[a], packed[a + 1], packed[a + 2], q[k])
    p[0] = px
    p[1] = py
    p[2] = pz
    er[0] = e0
    er[1] = e1
    er[2] = e2
    er[3] = e3
    return True


@njit(cache=True, fastmath=_FM)
def jac_packed(q, packed, jac):
    """The eq (7) Jacobian (6, n) of one joint vector on the packed model; returns False
    (jac untouched) when q has a non-finite value or not the model's n values."""
    n = (packed.shape[0] - 3) // 7
    if q.shape[0] != n or jac.shape[1] != n or not _packed_q_ok(q, n):
        return False
    nb = 3 * n
    npr = nb + 3 * (n + 1)
    e0, e1, e2, e3 = 1.0, 0.0, 0.0, 0.0
    px, py, pz = 0.0, 0.0, 0.0
    for k in range(n + 1):
        b = nb + 3 * k
        bx, by, bz = rotate_code(_code(packed[b], packed[b + 1], packed[b + 2]), e0, e1, e2,
                                 e3, packed[b], packed[b + 1], packed[b + 2])
        px += bx
        py += by
        pz += bz
        if k == n:
            break
        a = 3 * k
        wx, wy, wz = rotate(e0, e1, e2, e3, packed[a], packed[a + 1], packed[a + 2])
        jac[0, k] = wx
        jac[1, k] = wy
        jac[2, k] = wz
        jac[3, k] = px
        jac[4, k] = py
        jac[5, k] = pz
        if packed[npr + k] != 0.0:
            px += q[k] * wx
            py += q[k] * wy
            pz += q[k] * wz
        else:
            e0, e1, e2, e3 = turn_code(_code(packed[a], packed[a + 1], packed[a + 2]), e0, e1,
                                       e2, e3, packed[a], packed[a + 1], packed[a + 2], q[k])
    for k in range(n):
        _jac_column(packed[npr + k] != 0.0, jac[0, k], jac[1, k], jac[2, k], px - jac[3, k],
                    py - jac[4, k], pz - jac[5, k], jac[:, k])
    return True


def pack_model(axes: np.ndarray, bodies: np.ndarray, prism: np.ndarray) -> np.ndarray:
    """The packed layout of :func:`fk_pose_packed` (axes, bodies, prismatic flags)."""
    return np.concatenate([np.ravel(axes), np.ravel(bodies),
                           np.asarray(prism, dtype=np.float64)]).astype(np.float64)


def kernel_arrays(axes: np.ndarray, bodies: np.ndarray, prism: np.ndarray) -> tuple:
    """Contiguous copies of a model's arrays in the kernels' layout."""
    return (np.ascontiguousarray(axes, dtype=np.float64),
            np.ascontiguousarray(bodies, dtype=np.float64),
            np.ascontiguousarray(prism, dtype=np.bool_))
