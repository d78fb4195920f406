"""Compiled Monte Carlo kernel: the exact (nonlinear) deviations of many perturbed arms.

Each robot i has its own zero-reference axes u_{k,0}^(i) and body vectors b_{k,0}^(i); all
robots follow the same nominal joint trajectory q(t). For every robot the kernel evaluates
eqs (1)-(6) at every trajectory point and keeps max_t delta_p (eq 17) and max_t |e_eps|
(the norm of the vector part of the error rotation E_a * conj(E_d), i.e. sin(theta_eps / 2)).

Robots run in parallel threads (``prange``). Within a robot the T trajectory points are held
as structure-of-arrays and advance joint by joint, so every loop over t is branch-free and
vectorises (4-wide AVX); the robot's own axes and bodies are scalars in those loops. This is
3.3x faster than the former kernel (one pose at a time in registers, scalar code), measured
A/B in one process. A variant with the robots innermost was not faster (the per-robot axes
become vector loads). The half-angle sines and cosines of q(t) are shared by all robots and
computed once (unless per-robot joint offsets are given: then by the vectorising
:func:`zrp.kinematics._kernels.sincos`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from zrp.kinematics._kernels import sincos


@njit(inline="always", fastmath=True)
def _step(e0, e1, e2, e3, px, py, pz, bx, by, bz, ux, uy, uz, c, s):
    """p += R(E) b (eq 2) then E <- E * (cos(q/2), u sin(q/2)) (eqs 4-6), one pose."""
    cx = e2 * bz - e3 * by
    cy = e3 * bx - e1 * bz
    cz = e1 * by - e2 * bx
    px += bx + 2.0 * (e0 * cx + e2 * cz - e3 * cy)
    py += by + 2.0 * (e0 * cy + e3 * cx - e1 * cz)
    pz += bz + 2.0 * (e0 * cz + e1 * cy - e2 * cx)
    f1 = ux * s
    f2 = uy * s
    f3 = uz * s
    return (e0 * c - e1 * f1 - e2 * f2 - e3 * f3, e0 * f1 + c * e1 + e2 * f3 - e3 * f2,
            e0 * f2 + c * e2 + e3 * f1 - e1 * f3, e0 * f3 + c * e3 + e1 * f2 - e2 * f1,
            px, py, pz)


# nogil: on a Dask worker the event loop (heartbeats, the next task, sending results) keeps
# running while a chunk computes
@njit(cache=True, fastmath=True, parallel=True, nogil=True)
def mc_max_deviation(ch, sh, qv, axes, bodies, prism, offsets, use_offsets, pd, ed,
                     out_dp, out_s):
    """Per robot max_t delta_p and max_t sin(theta_eps / 2).

    Args:
        ch, sh: cos(q/2), sin(q/2) of the nominal joints, shape (n, T) (joint-major).
        qv: nominal joint values, shape (n, T) (prismatic displacements, and q for offsets).
        axes: perturbed axes u_{k,0}, shape (N, n, 3).
        bodies: perturbed body vectors b_{k,0}, shape (N, n + 1, 3).
        prism: prismatic mask, shape (n,).
        offsets: joint offsets (rad or length unit), shape (N, n) (read only if
            ``use_offsets``).
        pd, ed: desired (nominal) position (3, T) and Euler-Rodrigues parameters (4, T).
        out_dp, out_s: outputs, shape (N,).
    """
    nrob = axes.shape[0]
    n = axes.shape[1]
    nt = ch.shape[1]
    for i in prange(nrob):
        w = np.empty((9, nt))  # e0..e3, px, py, pz, then cos/sin of (q + offset)/2
        e0 = w[0]
        e1 = w[1]
        e2 = w[2]
        e3 = w[3]
        px = w[4]
        py = w[5]
        pz = w[6]
        cw = w[7]
        sw = w[8]
        ax = axes[i]
        bd = bodies[i]
        for t in range(nt):
            e0[t] = 1.0
            e1[t] = 0.0
            e2[t] = 0.0
            e3[t] = 0.0
            px[t] = 0.0
            py[t] = 0.0
            pz[t] = 0.0
        for k in range(n):
            bx = bd[k, 0]
            by = bd[k, 1]
            bz = bd[k, 2]
            ux = ax[k, 0]
            uy = ax[k, 1]
            uz = ax[k, 2]
            if prism[k]:
                qk = qv[k]
                for t in range(nt):
                    d = qk[t] + offsets[i, k] if use_offsets else qk[t]
                    a0 = e0[t]
                    a1 = e1[t]
                    a2 = e2[t]
                    a3 = e3[t]
                    _, _, _, _, x, y, z = _step(a0, a1, a2, a3, px[t], py[t], pz[t], bx, by,
                                                bz, 0.0, 0.0, 0.0, 1.0, 0.0)
                    _, _, _, _, wx, wy, wz = _step(a0, a1, a2, a3, 0.0, 0.0, 0.0, ux, uy, uz,
                                                   0.0, 0.0, 0.0, 1.0, 0.0)
                    px[t] = x + d * wx
                    py[t] = y + d * wy
                    pz[t] = z + d * wz
                continue
            if use_offsets:
                qk = qv[k]
                h = offsets[i, k]
                # inlined, so under this kernel's fastmath: the half angles are a few rad at
                # most (k <= 2 in the reduction), where reassociating the three-part
                # reduction costs < 1e-16. Not a call to the shared sincos_batch: numba
                # compiled that dispatcher under this caller's flags and cached it, which
                # broke its libm-exactness test for |x| ~ 100 (4e-12) in later callers.
                for t in range(nt):
                    sw[t], cw[t] = sincos(0.5 * (qk[t] + h))
                ck = cw
                sk = sw
            else:
                ck = ch[k]
                sk = sh[k]
            for t in range(nt):
                e0[t], e1[t], e2[t], e3[t], px[t], py[t], pz[t] = _step(
                    e0[t], e1[t], e2[t], e3[t], px[t], py[t], pz[t], bx, by, bz, ux, uy, uz,
                    ck[t], sk[t])
        # the tool's body vector, then eq (17) and the vector part of E_a * conj(E_d)
        bx = bd[n, 0]
        by = bd[n, 1]
        bz = bd[n, 2]
        mdp = 0.0
        ms = 0.0
        for t in range(nt):
            a0 = e0[t]
            a1 = e1[t]
            a2 = e2[t]
            a3 = e3[t]
            _, _, _, _, x, y, z = _step(a0, a1, a2, a3, px[t], py[t], pz[t], bx, by, bz,
                                        0.0, 0.0, 0.0, 1.0, 0.0)
            dx = x - pd[0, t]
            dy = y - pd[1, t]
            dz = z - pd[2, t]
            mdp = max(mdp, dx * dx + dy * dy + dz * dz)
            d0 = ed[0, t]
            d1 = -ed[1, t]
            d2 = -ed[2, t]
            d3 = -ed[3, t]
            v1 = a0 * d1 + d0 * a1 + a2 * d3 - a3 * d2
            v2 = a0 * d2 + d0 * a2 + a3 * d1 - a1 * d3
            v3 = a0 * d3 + d0 * a3 + a1 * d2 - a2 * d1
            ms = max(ms, v1 * v1 + v2 * v2 + v3 * v3)
        out_dp[i] = math.sqrt(mdp)
        out_s[i] = math.sqrt(ms)


#: Robots a first-order block holds in its accumulators (6 x 64 doubles: 3 KB, in L1).
FO_BLOCK = 64


# no fastmath: every robot's sums run in one fixed order (no reassociation), so a robot's
# maxima are the same bits whichever thread or worker computes its block
@njit(cache=True, parallel=True, nogil=True)
def first_order_maxima(jac, dxt, out_p, out_r):
    """Per robot max_t ||J_p(t) dx|| and max_t ||J_r(t) dx|| (first-order model, eq 18),
    without forming the (N, T, 6) deviations: blocks of FO_BLOCK robots in parallel threads,
    robots innermost (each parameter's row of the block is read once for the six rows of J,
    a constant trip count that vectorises), parameters with an all-zero column skipped. 10x
    faster than BLAS's (N, P) x (P, 6T) product followed by NumPy norms (5.5 -> 0.54 s for
    1e5 robots x 360 points on one core, measured side by side), the same values to 1e-15.

    Args:
        jac: identification Jacobian, shape (T, 6, P): rows 0-2 rotation, 3-5 position.
        dxt: parameter steps, robots last, zero-padded to a multiple of FO_BLOCK robots,
            shape (P, ceil(N / FO_BLOCK) * FO_BLOCK).
        out_p, out_r: per-robot maxima (length unit, rad), shape (N,), written.
    """
    n_t = jac.shape[0]
    n_p = jac.shape[2]
    n = out_p.shape[0]
    for b in prange(dxt.shape[1] // FO_BLOCK):
        lo = b * FO_BLOCK
        blk = dxt[:, lo:lo + FO_BLOCK].copy()  # this block's steps, contiguous
        a0 = np.empty(FO_BLOCK)
        a1 = np.empty(FO_BLOCK)
        a2 = np.empty(FO_BLOCK)
        a3 = np.empty(FO_BLOCK)
        a4 = np.empty(FO_BLOCK)
        a5 = np.empty(FO_BLOCK)
        best_p = np.zeros(FO_BLOCK)
        best_r = np.zeros(FO_BLOCK)
        for t in range(n_t):
            a0[:] = 0.0
            a1[:] = 0.0
            a2[:] = 0.0
            a3[:] = 0.0
            a4[:] = 0.0
            a5[:] = 0.0
            for p in range(n_p):
                j0 = jac[t, 0, p]
                j1 = jac[t, 1, p]
                j2 = jac[t, 2, p]
                j3 = jac[t, 3, p]
                j4 = jac[t, 4, p]
                j5 = jac[t, 5, p]
                if j0 == 0.0 and j1 == 0.0 and j2 == 0.0 and j3 == 0.0 and j4 == 0.0 \
                        and j5 == 0.0:
                    continue
                row = blk[p]
                for i in range(FO_BLOCK):
                    v = row[i]
                    a0[i] += j0 * v
                    a1[i] += j1 * v
                    a2[i] += j2 * v
                    a3[i] += j3 * v
                    a4[i] += j4 * v
                    a5[i] += j5 * v
            for i in range(FO_BLOCK):
                r2 = a0[i] * a0[i] + a1[i] * a1[i] + a2[i] * a2[i]
                p2 = a3[i] * a3[i] + a4[i] * a4[i] + a5[i] * a5[i]
                best_r[i] = max(best_r[i], r2)
                best_p[i] = max(best_p[i], p2)
        for i in range(min(FO_BLOCK, n - lo)):
            out_r[lo + i] = math.sqrt(best_r[i])
            out_p[lo + i] = math.sqrt(best_p[i])
