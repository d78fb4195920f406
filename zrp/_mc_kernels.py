"""Compiled Monte Carlo kernel: the exact (nonlinear) deviations of many perturbed arms.

Each robot i has its own zero-reference axes u_{k,0}^(i) and body vectors b_{k,0}^(i); all
robots follow the same nominal joint trajectory q(t). For every robot the kernel evaluates
eqs (1)-(6) at every trajectory point and keeps max_t delta_p (eq 17) and max_t |e_eps|
(the vector part of the error rotation E_a * conj(E_d), i.e. sin(theta_eps / 2)).

Layout: robots are processed in blocks of ``BLOCK`` in structure-of-arrays form (robot index
last), so the innermost loops run over robots with no dependencies and compile to SIMD code;
blocks run in parallel threads. The half-angle sines and cosines of q(t) are shared by all
robots and computed once (unless per-robot joint offsets are given).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

BLOCK = 64


@njit(cache=True, fastmath=True, parallel=True)
def mc_max_deviation(ch, sh, qv, axes, bodies, prism, offsets, use_offsets, pd, ed,
                     out_dp, out_s):
    """Per robot max_t delta_p and max_t sin(theta_eps / 2).

    Args:
        ch, sh: cos(q/2), sin(q/2) of the nominal joints, shape (T, n).
        qv: nominal joint values, shape (T, n) (prismatic displacements, and q for offsets).
        axes: perturbed axes, shape (n, 3, N) (robot index last).
        bodies: perturbed body vectors, shape (n + 1, 3, N).
        prism: prismatic mask, shape (n,).
        offsets: joint offsets, shape (n, N) (read only if ``use_offsets``).
        pd, ed: desired (nominal) position (T, 3) and Euler-Rodrigues parameters (T, 4).
        out_dp, out_s: outputs, shape (N,).
    """
    n = axes.shape[0]
    nrob = axes.shape[2]
    nt = ch.shape[0]
    nblocks = (nrob + BLOCK - 1) // BLOCK
    for blk in prange(nblocks):
        i0 = blk * BLOCK
        m = min(BLOCK, nrob - i0)
        e0 = np.empty(m)
        e1 = np.empty(m)
        e2 = np.empty(m)
        e3 = np.empty(m)
        px = np.empty(m)
        py = np.empty(m)
        pz = np.empty(m)
        cc = np.empty(m)
        ss = np.empty(m)
        mdp = np.zeros(m)
        ms = np.zeros(m)
        for t in range(nt):
            for j in range(m):
                e0[j] = 1.0
                e1[j] = 0.0
                e2[j] = 0.0
                e3[j] = 0.0
                px[j] = 0.0
                py[j] = 0.0
                pz[j] = 0.0
            for k in range(n + 1):
                # eq (2): p += R_{k-1} b_{k,0} = v + 2 e0 (e x v) + 2 e x (e x v)
                for j in range(m):
                    bx = bodies[k, 0, i0 + j]
                    by = bodies[k, 1, i0 + j]
                    bz = bodies[k, 2, i0 + j]
                    a0 = e0[j]
                    a1 = e1[j]
                    a2 = e2[j]
                    a3 = e3[j]
                    cx = a2 * bz - a3 * by
                    cy = a3 * bx - a1 * bz
                    cz = a1 * by - a2 * bx
                    px[j] += bx + 2.0 * (a0 * cx + a2 * cz - a3 * cy)
                    py[j] += by + 2.0 * (a0 * cy + a3 * cx - a1 * cz)
                    pz[j] += bz + 2.0 * (a0 * cz + a1 * cy - a2 * cx)
                if k == n:
                    break
                if prism[k]:
                    for j in range(m):
                        ux = axes[k, 0, i0 + j]
                        uy = axes[k, 1, i0 + j]
                        uz = axes[k, 2, i0 + j]
                        a0 = e0[j]
                        a1 = e1[j]
                        a2 = e2[j]
                        a3 = e3[j]
                        cx = a2 * uz - a3 * uy
                        cy = a3 * ux - a1 * uz
                        cz = a1 * uy - a2 * ux
                        d = qv[t, k]
                        if use_offsets:
                            d += offsets[k, i0 + j]
                        px[j] += d * (ux + 2.0 * (a0 * cx + a2 * cz - a3 * cy))
                        py[j] += d * (uy + 2.0 * (a0 * cy + a3 * cx - a1 * cz))
                        pz[j] += d * (uz + 2.0 * (a0 * cz + a1 * cy - a2 * cx))
                    continue
                if use_offsets:
                    for j in range(m):
                        h = 0.5 * (qv[t, k] + offsets[k, i0 + j])
                        cc[j] = math.cos(h)
                        ss[j] = math.sin(h)
                else:
                    c = ch[t, k]
                    s = sh[t, k]
                    for j in range(m):
                        cc[j] = c
                        ss[j] = s
                # eqs (4)-(6): E <- E * (cos(q/2), u sin(q/2))
                for j in range(m):
                    c = cc[j]
                    s = ss[j]
                    f1 = axes[k, 0, i0 + j] * s
                    f2 = axes[k, 1, i0 + j] * s
                    f3 = axes[k, 2, i0 + j] * s
                    a0 = e0[j]
                    a1 = e1[j]
                    a2 = e2[j]
                    a3 = e3[j]
                    e0[j] = a0 * c - a1 * f1 - a2 * f2 - a3 * f3
                    e1[j] = a0 * f1 + c * a1 + a2 * f3 - a3 * f2
                    e2[j] = a0 * f2 + c * a2 + a3 * f1 - a1 * f3
                    e3[j] = a0 * f3 + c * a3 + a1 * f2 - a2 * f1
            # eq (17) and the vector part of E_a * conj(E_d)
            dx0 = pd[t, 0]
            dy0 = pd[t, 1]
            dz0 = pd[t, 2]
            d0 = ed[t, 0]
            d1 = -ed[t, 1]
            d2 = -ed[t, 2]
            d3 = -ed[t, 3]
            for j in range(m):
                dx = px[j] - dx0
                dy = py[j] - dy0
                dz = pz[j] - dz0
                dp2 = dx * dx + dy * dy + dz * dz
                if dp2 > mdp[j]:
                    mdp[j] = dp2
                a0 = e0[j]
                a1 = e1[j]
                a2 = e2[j]
                a3 = e3[j]
                v1 = a0 * d1 + d0 * a1 + a2 * d3 - a3 * d2
                v2 = a0 * d2 + d0 * a2 + a3 * d1 - a1 * d3
                v3 = a0 * d3 + d0 * a3 + a1 * d2 - a2 * d1
                s2 = v1 * v1 + v2 * v2 + v3 * v3
                if s2 > ms[j]:
                    ms[j] = s2
        for j in range(m):
            out_dp[i0 + j] = math.sqrt(mdp[j])
            out_s[i0 + j] = math.sqrt(ms[j])
