"""Compiled Monte Carlo kernel: the exact (nonlinear) deviations of many perturbed arms.

Each robot i has its own zero-reference axes u_{k,0}^(i) and body vectors b_{k,0}^(i); all
robots follow the same nominal joint trajectory q(t). For every robot the kernel evaluates
eqs (1)-(6) at every trajectory point and keeps max_t delta_p (eq 17) and max_t |e_eps|
(the norm of the vector part of the error rotation E_a * conj(E_d), i.e. sin(theta_eps / 2)).

Robots run in parallel threads (``prange``); each robot's state stays in registers. The
half-angle sines and cosines of q(t) are shared by all robots and computed once (unless
per-robot joint offsets are given). A structure-of-arrays variant (robots innermost, for SIMD)
was measured in the same benchmark and was not faster on this machine.
"""

from __future__ import annotations

import math

from numba import njit, prange


@njit(cache=True, fastmath=True, parallel=True)
def mc_max_deviation(ch, sh, qv, axes, bodies, prism, offsets, use_offsets, pd, ed,
                     out_dp, out_s):
    """Per robot max_t delta_p and max_t sin(theta_eps / 2).

    Args:
        ch, sh: cos(q/2), sin(q/2) of the nominal joints, shape (T, n).
        qv: nominal joint values, shape (T, n) (prismatic displacements, and q for offsets).
        axes: perturbed axes u_{k,0}, shape (N, n, 3).
        bodies: perturbed body vectors b_{k,0}, shape (N, n + 1, 3).
        prism: prismatic mask, shape (n,).
        offsets: joint offsets, shape (N, n) (read only if ``use_offsets``).
        pd, ed: desired (nominal) position (T, 3) and Euler-Rodrigues parameters (T, 4).
        out_dp, out_s: outputs, shape (N,).
    """
    nrob = axes.shape[0]
    n = axes.shape[1]
    nt = ch.shape[0]
    for i in prange(nrob):
        ax = axes[i]
        bd = bodies[i]
        mdp = 0.0
        ms = 0.0
        for t in range(nt):
            e0 = 1.0
            e1 = 0.0
            e2 = 0.0
            e3 = 0.0
            px = 0.0
            py = 0.0
            pz = 0.0
            for k in range(n + 1):
                # eq (2): p += R_{k-1} b_{k,0} = v + 2 e0 (e x v) + 2 e x (e x v)
                bx = bd[k, 0]
                by = bd[k, 1]
                bz = bd[k, 2]
                cx = e2 * bz - e3 * by
                cy = e3 * bx - e1 * bz
                cz = e1 * by - e2 * bx
                px += bx + 2.0 * (e0 * cx + e2 * cz - e3 * cy)
                py += by + 2.0 * (e0 * cy + e3 * cx - e1 * cz)
                pz += bz + 2.0 * (e0 * cz + e1 * cy - e2 * cx)
                if k == n:
                    break
                ux = ax[k, 0]
                uy = ax[k, 1]
                uz = ax[k, 2]
                if prism[k]:
                    d = qv[t, k]
                    if use_offsets:
                        d += offsets[i, k]
                    cx = e2 * uz - e3 * uy
                    cy = e3 * ux - e1 * uz
                    cz = e1 * uy - e2 * ux
                    px += d * (ux + 2.0 * (e0 * cx + e2 * cz - e3 * cy))
                    py += d * (uy + 2.0 * (e0 * cy + e3 * cx - e1 * cz))
                    pz += d * (uz + 2.0 * (e0 * cz + e1 * cy - e2 * cx))
                    continue
                if use_offsets:
                    h = 0.5 * (qv[t, k] + offsets[i, k])
                    c = math.cos(h)
                    s = math.sin(h)
                else:
                    c = ch[t, k]
                    s = sh[t, k]
                # eqs (4)-(6): E <- E * (cos(q/2), u sin(q/2))
                f1 = ux * s
                f2 = uy * s
                f3 = uz * s
                a0 = e0
                a1 = e1
                a2 = e2
                a3 = e3
                e0 = a0 * c - a1 * f1 - a2 * f2 - a3 * f3
                e1 = a0 * f1 + c * a1 + a2 * f3 - a3 * f2
                e2 = a0 * f2 + c * a2 + a3 * f1 - a1 * f3
                e3 = a0 * f3 + c * a3 + a1 * f2 - a2 * f1
            # eq (17) and the vector part of E_a * conj(E_d)
            dx = px - pd[t, 0]
            dy = py - pd[t, 1]
            dz = pz - pd[t, 2]
            dp2 = dx * dx + dy * dy + dz * dz
            if dp2 > mdp:
                mdp = dp2
            d0 = ed[t, 0]
            d1 = -ed[t, 1]
            d2 = -ed[t, 2]
            d3 = -ed[t, 3]
            v1 = e0 * d1 + d0 * e1 + e2 * d3 - e3 * d2
            v2 = e0 * d2 + d0 * e2 + e3 * d1 - e1 * d3
            v3 = e0 * d3 + d0 * e3 + e1 * d2 - e2 * d1
            s2 = v1 * v1 + v2 * v2 + v3 * v3
            if s2 > ms:
                ms = s2
        out_dp[i] = math.sqrt(mdp)
        out_s[i] = math.sqrt(ms)
