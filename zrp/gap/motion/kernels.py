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
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["first_order_lag", "play"]

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
