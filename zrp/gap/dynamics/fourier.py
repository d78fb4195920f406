"""Finite Fourier series joint trajectories (Swevers et al. 1997), the exciting command of
the dynamic gap (eq. X1), with omega_l = 2 pi f0 l::

    q_k(t) = q0_k + sum_l a_kl / omega_l sin(omega_l t) - b_kl / omega_l cos(omega_l t)

It is periodic with period 1 / f0; the coefficients are projected so that it starts at q0 at
rest (q(0) = q0, qd(0) = 0, qdd(0) = 0: sum_l b_kl / omega_l = 0, sum_l a_kl = 0,
sum_l b_kl omega_l = 0), and scaled into position, velocity and acceleration limits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.limits import MAX_HARMONICS  # largest number of harmonics of a series

__all__ = ["MAX_HARMONICS", "Fourier", "random_fourier"]

_CHUNK = 1 << 15


@dataclass(frozen=True)
class Fourier:
    """q0 (n,), a and b (n, L), f0 in Hz (eq. X1)."""

    q0: F64
    a: F64
    b: F64
    f0_hz: float

    @property
    def omegas(self) -> F64:
        return 2.0 * np.pi * self.f0_hz * np.arange(1, self.a.shape[1] + 1)

    def evaluate(self, t: F64) -> tuple[F64, F64, F64]:
        """q, qd, qdd at times ``t`` (s), each (S, n)."""
        t = np.asarray(t, dtype=float)
        q, qd, qdd = (np.empty((t.size, self.q0.size)) for _ in range(3))
        for i in range(0, t.size, _CHUNK):  # bounded temporaries: (chunk, L) at a time
            part = slice(i, i + _CHUNK)
            q[part], qd[part], qdd[part] = self._at(t[part])
        return q, qd, qdd

    def _at(self, t: F64) -> tuple[F64, F64, F64]:
        w = self.omegas
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        q = self.q0 + s @ (self.a / w).T - c @ (self.b / w).T
        qd = c @ self.a.T + s @ self.b.T
        qdd = -s @ (self.a * w).T + c @ (self.b * w).T
        return q, qd, qdd

    def peaks(self, n_samples: int = 2000) -> tuple[F64, F64, F64]:
        """Upper bounds of max |q - q0|, max |qd|, max |qdd| over one period, each (n,).

        Each is a trigonometric polynomial of degree L (the harmonics) in x = omega_1 t; its
        largest |value| on M equally spaced samples (M = max(``n_samples``, 32 L)) lies
        within ||p|| (1 - pi^2 L^2 / (2 M^2)) of its true peak ||p|| (Bernstein's inequality
        ||p''|| <= L^2 ||p|| and a sample within pi / M of the peak), so the sampled peak
        divided by that factor bounds the peak between the samples too.
        """
        L = self.a.shape[1]
        m = max(int(n_samples), 32 * L)
        t = np.linspace(0.0, 1.0 / self.f0_hz, m, endpoint=False)
        q, qd, qdd = self.evaluate(t)
        k = 1.0 / (1.0 - (np.pi * L / m) ** 2 / 2.0)
        return (k * np.abs(q - self.q0).max(0), k * np.abs(qd).max(0), k * np.abs(qdd).max(0))


def _rest_projector(w: F64) -> F64:
    """Projector of coefficient vectors (a_1..a_L, b_1..b_L) onto the start-at-rest
    conditions (module docstring)."""
    L = w.size
    c = np.zeros((3, 2 * L))
    c[0, :L] = 1.0
    c[1, L:] = 1.0 / w
    c[2, L:] = w
    return np.eye(2 * L) - np.linalg.pinv(c) @ c


def scale_into(f: Fourier, q_amp: F64, qd_max: F64, qdd_max: F64) -> Fourier:
    """``f`` with each joint's coefficients scaled down (or up) to meet its tightest limit."""
    dq, dqd, dqdd = f.peaks()
    with np.errstate(divide="ignore"):
        k = np.min(np.stack([q_amp / dq, qd_max / dqd, qdd_max / dqdd]), axis=0)
    k = np.where(np.isfinite(k), k, 0.0)
    return Fourier(f.q0, f.a * k[:, None], f.b * k[:, None], f.f0_hz)


def random_fourier(q0: F64, q_amp: F64, qd_max: F64, qdd_max: F64, *, harmonics: int = 5,
                   f0_hz: float = 0.1, seed: int | np.random.Generator = 0) -> Fourier:
    """A random exciting trajectory about q0 within the limits (each (n,))."""
    if isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)) \
            or not 2 <= harmonics <= MAX_HARMONICS:
        raise InputError(f"harmonics: {harmonics!r}; expected a whole number from 2 (the "
                         "start-at-rest conditions take three coefficients a joint) to "
                         f"{MAX_HARMONICS} (the stated bound on the series' size)")
    rng = np.random.default_rng(seed)
    q0 = np.asarray(q0, dtype=float)
    n = q0.size
    w = 2.0 * np.pi * f0_hz * np.arange(1, harmonics + 1)
    proj = _rest_projector(w)
    coef = rng.normal(size=(n, 2 * harmonics)) @ proj.T
    f = Fourier(q0, coef[:, :harmonics], coef[:, harmonics:], f0_hz)
    return scale_into(f, np.broadcast_to(q_amp, n), np.broadcast_to(qd_max, n),
                      np.broadcast_to(qdd_max, n))
