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
  y'' + 2 zeta omega y' + omega^2 y = -u'' (eq. M5), with dy/domega and dy/dzeta from the
  sensitivity equations, all three integrated exactly for input linear between samples
  (first-order-hold discretisation of the augmented linear system by ``scipy.linalg.expm``).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

__all__ = ["first_order_lag", "mode_response", "play"]

F64 = NDArray[np.float64]


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


def mode_response(t: F64, f: F64, omega: float, zeta: float, derivatives: bool = True
                  ) -> tuple[F64, F64, F64]:
    """The response y of the mode y'' + 2 zeta omega y' + omega^2 y = f (eq. M5) and its
    derivatives dy/domega, dy/dzeta, exact for f linear between samples.

    Args:
        t: sample times, s, strictly increasing, shape (S,).
        f: forcing (the negated commanded acceleration, rad/s^2), shape (S,).
        omega: natural angular frequency, rad/s, > 0; zeta: damping ratio, >= 0.
        derivatives: False skips the sensitivities (three times faster; they come back as
            NaN).

    Returns:
        y (rad), dy/domega (rad s), dy/dzeta (rad), shape (S,) each; the mode starts in
        static equilibrium with f(t_0) (y = f / omega^2, at rest).
    """
    t = np.ascontiguousarray(t, dtype=float)
    f = np.ascontiguousarray(f, dtype=float)
    m = 6 if derivatives else 2
    a = _system(float(omega), float(zeta))[:m, :m]
    h = np.diff(t)
    hs, group = np.unique(np.round(h, 12), return_inverse=True)
    if hs.size > 64:  # irregular stamps: one discretisation per step
        hs, group = h, np.arange(h.size)
    phi = np.empty((hs.size, m, m))
    g0 = np.empty((hs.size, m))
    g1 = np.empty((hs.size, m))
    big = np.zeros((m + 2, m + 2))
    for i, hi in enumerate(hs):
        big[:m, :m] = a * hi
        big[1, m] = hi  # input f enters y''
        big[m, m + 1] = 1.0  # f(t) = f_i + (f_{i+1} - f_i) s / h
        e = expm(big)
        phi[i] = e[:m, :m]
        g0[i] = e[:m, m] - e[:m, m + 1]
        g1[i] = e[:m, m + 1]
    w2 = omega * omega
    z0 = np.array([f[0] / w2, 0.0, -2.0 * f[0] / (w2 * omega), 0.0, 0.0, 0.0])[:m]
    z = _mode(group.astype(np.int64).ravel(), phi, g0, g1, f, z0)
    if not derivatives:
        nan = np.full(f.size, np.nan)
        return z[:, 0], nan, nan
    return z[:, 0], z[:, 2], z[:, 4]
