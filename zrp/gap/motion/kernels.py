"""Compiled recursions of the motion effects, each with its exact derivative.

Both act on a sampled joint signal u (commanded joint values, S samples at times t) and
return the joint's actual value y and dy/dparameter, shape (S,) each, exactly for the
discrete model (so the analytic Jacobian equals the finite difference of the same code):

* :func:`first_order_lag`: tau y' + y = u with u linear between samples (eq. M1, exact
  zero-order-hold-free solution): y_{i+1} = a y_i + b u_i + c u_{i+1}, a = exp(-h/tau),
  g = (tau/h)(1 - a), b = g - a, c = 1 - g; y_0 = u_0 (at rest on the command).
* :func:`play`: the play (hysteresis) operator of half-width r (eq. M2), the quasi-static
  path of a stiff position servo with Coulomb friction: y_i = min(max(y_{i-1}, u_i - r),
  u_i + r), y_0 = u_0.
* :func:`mode_response`: a lightly damped mode driven by the commanded acceleration,
  y'' + (2 zeta omega + b(t)) y' + (omega^2 + s(t)) y = -u'' (eq. M5; s, b the arm's own
  stiffness and damping per unit inertia along the path, eq. M6, zero by default), with
  dy/domega and dy/dzeta from the sensitivity equations, all three integrated exactly for
  input linear between samples (first-order-hold discretisation of the augmented linear
  system by ``scipy.linalg.expm``); the time-varying part -(s y + b y') enters as an input
  linear between samples, implicitly at the step's end (one small linear solve per step).
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from zrp.arrays import F64

__all__ = ["first_order_lag", "mode_response", "play"]



@numba.njit(cache=True)
def _lag(t: F64, u: F64, tau: float) -> tuple[F64, F64]:  # pragma: no cover - compiled
    s = u.size
    y = np.empty(s)
    dy = np.empty(s)
    y[0] = u[0]
    dy[0] = 0.0
    for i in range(s - 1):
        h = t[i + 1] - t[i]
        x = h / tau
        a = math.exp(-x)
        g = (1.0 - a) / x
        da = a * h / (tau * tau)
        dg = (1.0 - a) / h - a / tau
        b = g - a
        c = 1.0 - g
        y[i + 1] = a * y[i] + b * u[i] + c * u[i + 1]
        dy[i + 1] = a * dy[i] + da * y[i] + (dg - da) * u[i] - dg * u[i + 1]
    return y, dy


def first_order_lag(t: F64, u: F64, tau: float) -> tuple[F64, F64]:
    """The first-order servo response y to command u and dy/dtau (eq. M1).

    Args:
        t: sample times, s, strictly increasing, shape (S,).
        u: command, shape (S,).
        tau: time constant, s; tau <= 1e-9 s gives the limit y = u - tau u' (first order,
            valid for a tiny or negative estimate), dy/dtau = -u'.
    """
    t = np.ascontiguousarray(t, dtype=float)
    u = np.ascontiguousarray(u, dtype=float)
    if tau <= 1e-9:
        du = np.gradient(u, t)
        return u - tau * du, -du
    return _lag(t, u, float(tau))


@numba.njit(cache=True)
def _play(u: F64, r: float) -> tuple[F64, F64]:  # pragma: no cover - compiled
    s = u.size
    y = np.empty(s)
    dy = np.empty(s)
    y[0] = u[0]
    dy[0] = 0.0
    for i in range(1, s):
        lo = u[i] - r
        hi = u[i] + r
        if y[i - 1] < lo:
            y[i] = lo
            dy[i] = -1.0
        elif y[i - 1] > hi:
            y[i] = hi
            dy[i] = 1.0
        else:
            y[i] = y[i - 1]
            dy[i] = dy[i - 1]
    return y, dy


def play(u: F64, r: float) -> tuple[F64, F64]:
    """The play operator y of half-width r on u and dy/dr (eq. M2); r < 0 is treated as its
    linear continuation y = u + r dy/dr|_{r=0+}."""
    u = np.ascontiguousarray(u, dtype=float)
    if r <= 0.0:
        _, d0 = _play(u, 1e-12)
        return u + r * d0, d0
    return _play(u, float(r))


@numba.njit(cache=True)
def _mode(group: NDArray[np.int64], phi: F64, g0: F64, g1: F64, f: F64, z0: F64
          ) -> F64:  # pragma: no cover - compiled
    s = f.size
    m = z0.size
    z = np.empty((s, m))
    z[0] = z0
    for i in range(s - 1):
        k = group[i]
        for r in range(m):
            acc = g0[k, r] * f[i] + g1[k, r] * f[i + 1]
            for c in range(m):
                acc += phi[k, r, c] * z[i, c]
            z[i + 1, r] = acc
    return z


@numba.njit(cache=True)
def _mode_tv(group: NDArray[np.int64], phi: F64, g0: F64, g1: F64, f: F64, z0: F64,
             stiff: F64, damp: F64) -> F64:  # pragma: no cover - compiled
    """The step z+ = phi z + G0 w + G1 w+ with w the input of the velocity rows (1, 3, 5):
    w = (f - s y - b y', -s y_omega - b y_omega', -s y_zeta - b y_zeta'); g0, g1 hold G0,
    G1, shape (groups, m, m/2). The end-of-step w+ depends on z+: (I + G1 P+) z+ = rhs."""
    s = f.size
    m = z0.size
    q = m // 2
    z = np.empty((s, m))
    z[0] = z0
    lhs = np.empty((m, m))
    rhs = np.empty(m)
    w = np.empty(q)
    for i in range(s - 1):
        k = group[i]
        for j in range(q):
            w[j] = -stiff[i] * z[i, 2 * j] - damp[i] * z[i, 2 * j + 1]
        w[0] += f[i]
        for r in range(m):
            acc = g1[k, r, 0] * f[i + 1]
            for c in range(m):
                acc += phi[k, r, c] * z[i, c]
            for j in range(q):
                acc += g0[k, r, j] * w[j]
            rhs[r] = acc
            for c in range(m):
                lhs[r, c] = 1.0 if r == c else 0.0
            for j in range(q):
                lhs[r, 2 * j] += g1[k, r, j] * stiff[i + 1]
                lhs[r, 2 * j + 1] += g1[k, r, j] * damp[i + 1]
        # Gaussian elimination without pivoting: lhs = I + G1 P is within a few 1e-3 of I
        for c in range(m):
            for r in range(c + 1, m):
                x = lhs[r, c] / lhs[c, c]
                if x != 0.0:
                    for cc in range(c, m):
                        lhs[r, cc] -= x * lhs[c, cc]
                    rhs[r] -= x * rhs[c]
        for r in range(m - 1, -1, -1):
            acc = rhs[r]
            for c in range(r + 1, m):
                acc -= lhs[r, c] * z[i + 1, c]
            z[i + 1, r] = acc / lhs[r, r]
    return z


def _system(omega: float, zeta: float) -> F64:
    """The augmented state matrix of z = (y, y', y_omega, y_omega', y_zeta, y_zeta')."""
    w2, c = omega * omega, 2.0 * zeta * omega
    a = np.zeros((6, 6))
    for b in (0, 2, 4):
        a[b, b + 1] = 1.0
        a[b + 1, b] = -w2
        a[b + 1, b + 1] = -c
    a[3, 0], a[3, 1] = -2.0 * omega, -2.0 * zeta  # d/domega of -w2 y - c y'
    a[5, 1] = -2.0 * omega                         # d/dzeta of -c y'
    return a


def mode_response(t: F64, f: F64, omega: float, zeta: float, derivatives: bool = True,
                  stiffness: F64 | None = None, damping: F64 | None = None
                  ) -> tuple[F64, F64, F64]:
    """The response y of the mode y'' + (2 zeta omega + b) y' + (omega^2 + s) y = f (eq. M5,
    M6) and its derivatives dy/domega, dy/dzeta, exact for f linear between samples (and, with
    s or b, for the input -(s y + b y') linear between samples).

    Args:
        t: sample times, s, strictly increasing, shape (S,).
        f: forcing (the negated commanded acceleration, rad/s^2), shape (S,).
        omega: natural angular frequency, rad/s, > 0; zeta: damping ratio, >= 0.
        derivatives: False skips the sensitivities (three times faster; they come back as
            NaN).
        stiffness, damping: s(t) (1/s^2) and b(t) (1/s), shape (S,): the arm's own stiffness
            and damping of the joint per unit inertia along the path (gravity's and the
            velocity coupling's, ``mjcf.mode_terms``); None: zero.

    Returns:
        y (rad), dy/domega (rad s), dy/dzeta (rad), shape (S,) each; the mode starts in
        static equilibrium with f(t_0) (y = f / (omega^2 + s), at rest).
    """
    t = np.ascontiguousarray(t, dtype=float)
    f = np.ascontiguousarray(f, dtype=float)
    m = 6 if derivatives else 2
    h = np.diff(t)
    hs, group = np.unique(np.round(h, 12), return_inverse=True)
    if hs.size > 64:  # irregular stamps: one discretisation per step
        hs, group = h, np.arange(h.size)
        phi, g0, g1 = _discretise(_system(float(omega), float(zeta))[:m, :m], hs)
    else:  # the profile grid repeats (omega, zeta) for every joint: cached
        phi, g0, g1 = _discretised(float(omega), float(zeta), tuple(hs.tolist()), m)
    if stiffness is not None or damping is not None:
        sb = [np.zeros(f.size) if v is None else np.ascontiguousarray(v, dtype=float)
              for v in (stiffness, damping)]
        return _varying(phi, g0, g1, group, f, float(omega), sb[0], sb[1], derivatives)
    g0, g1 = np.ascontiguousarray(g0[:, :, 0]), np.ascontiguousarray(g1[:, :, 0])
    w2 = omega * omega
    z0 = np.array([f[0] / w2, 0.0, -2.0 * f[0] / (w2 * omega), 0.0, 0.0, 0.0])[:m]
    z = _mode(group.astype(np.int64).ravel(), phi, g0, g1, f, z0)
    if not derivatives:
        nan = np.full(f.size, np.nan)
        return z[:, 0], nan, nan
    return z[:, 0], z[:, 2], z[:, 4]


@functools.lru_cache(maxsize=512)
def _discretised(omega: float, zeta: float, hs: tuple[float, ...], m: int
                 ) -> tuple[F64, F64, F64]:
    """:func:`_discretise` of the mode (omega, zeta) for the step sizes ``hs``, cached."""
    out = _discretise(_system(omega, zeta)[:m, :m], np.array(hs))
    for x in out:
        x.setflags(write=False)
    return out


def _discretise(a: F64, hs: F64) -> tuple[F64, F64, F64]:
    """The first-order-hold discretisation of z' = a z + E w(t), w linear between samples
    and entering the velocity rows 1, 3, 5 (E), per step size: phi (H, m, m) and G0, G1
    (H, m, m/2) with z+ = phi z + G0 w + G1 w+ (``scipy.linalg.expm`` of the block matrix)."""
    m = a.shape[0]
    q = m // 2
    phi = np.empty((hs.size, m, m))
    g0 = np.empty((hs.size, m, q))
    g1 = np.empty((hs.size, m, q))
    big = np.zeros((m + 2 * q, m + 2 * q))
    big[m:m + q, m + q:] = np.eye(q)  # w(t) = w_i + (w_{i+1} - w_i) s / h
    for i, hi in enumerate(hs):
        big[:m, :m] = a * hi
        for j in range(q):
            big[2 * j + 1, m + j] = hi  # input j enters the velocity row 2j + 1
        e = expm(big)
        phi[i] = e[:m, :m]
        g0[i] = e[:m, m:m + q] - e[:m, m + q:]
        g1[i] = e[:m, m + q:]
    return phi, g0, g1


def _varying(phi: F64, g0: F64, g1: F64, group: NDArray[np.intp], f: F64, omega: float,
             stiff: F64, damp: F64, derivatives: bool) -> tuple[F64, F64, F64]:
    """:func:`mode_response` with the time-varying stiffness and damping (eq. M6)."""
    if stiff.shape != f.shape or damp.shape != f.shape:
        raise ValueError(f"stiffness, damping: expected shape {f.shape}, got {stiff.shape}, "
                         f"{damp.shape}")
    m = phi.shape[1]
    k = omega * omega + stiff[0]
    z0 = np.array([f[0] / k, 0.0, -2.0 * omega * f[0] / (k * k), 0.0, 0.0, 0.0])[:m]
    z = _mode_tv(group.astype(np.int64).ravel(), phi, g0, g1, f, z0, stiff, damp)
    if not derivatives:
        nan = np.full(f.size, np.nan)
        return z[:, 0], nan, nan
    return z[:, 0], z[:, 2], z[:, 4]
