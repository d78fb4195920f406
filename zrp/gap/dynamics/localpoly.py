"""Savitzky-Golay on the real time axis: the local polynomial fit of a segment whose time
stamps jitter.

At each sample i a polynomial of degree ``polyorder`` in (t - t_i) is fitted by least squares
to the ``w`` samples around it (the first or last ``w`` near the segment's ends, as
:func:`scipy.signal.savgol_filter`'s ``mode="interp"``), on the samples' own time stamps, and
its value and derivatives at t_i are taken (eq. D1 of :mod:`zrp.gap.dynamics.states`). On a
uniform grid this is exactly Savitzky-Golay, and then :func:`scipy.signal.savgol_filter` is
called (the fast path); with jitter nothing is resampled or interpolated, so no sample is
invented and the noise stays that of the measured samples.

The fit's centre weight h0_i (the leverage of sample i in its own smoothing) is returned with
it: the noise estimate (eq. N1) divides the residual's variance by 1 - h0.

Cost: about 2 S w (p + 1) (n + 2) flops per segment of S samples and n channels (the normal
equations accumulated over the window), in chunks of bounded memory (about 32 MB).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import savgol_coeffs, savgol_filter

from zrp.arrays import F64

__all__ = ["UNIFORM", "local_fit"]

#: Steps within this relative spread of the median count as a uniform grid.
UNIFORM = 1e-6
_CHUNK_FLOATS = 4_000_000


def _uniform(t: F64) -> bool:
    dt = np.diff(t)
    step = float(np.median(dt))
    return bool(np.max(np.abs(dt - step)) <= UNIFORM * step)


def _savgol(t: F64, y: F64, w: int, polyorder: int, derivs: tuple[int, ...]
            ) -> tuple[list[F64], F64]:
    dt = float(np.median(np.diff(t)))
    out = [savgol_filter(y, w, polyorder, deriv=d, delta=dt, axis=0, mode="interp")
           for d in derivs]
    h0 = float(savgol_coeffs(w, polyorder)[w // 2])
    return out, np.full(t.size, h0)


def _chunk(t: F64, y: F64, centres: np.ndarray, w: int, polyorder: int, scale: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (C, p+1, n) of the local fits at ``centres``, and their centre weights.

    The normal equations are accumulated over the window's offsets (moments of x and x^k y),
    so no (C, w, n) block is ever formed."""
    p = polyorder + 1
    start = np.clip(centres - w // 2, 0, t.size - w)
    tc = t[centres]
    moments = np.zeros((centres.size, 2 * p - 1))
    rhs = np.zeros((centres.size, p, y.shape[1]))
    xp = np.ones((centres.size, 2 * p - 1))
    for j in range(w):
        x = (t[start + j] - tc) / scale
        for k in range(1, 2 * p - 1):
            np.multiply(xp[:, k - 1], x, out=xp[:, k])
        moments += xp
        rhs += xp[:, :p, None] * y[start + j][:, None, :]
    ginv = np.linalg.inv(moments[:, np.add.outer(np.arange(p), np.arange(p))])  # Hankel
    # the centre is x = 0, where the basis is (1, 0, .., 0): its weight is ginv[0, 0]
    return ginv @ rhs, ginv[:, 0, 0]


def local_fit(t: F64, y: F64, w: int, polyorder: int, derivs: tuple[int, ...] = (0,)
              ) -> tuple[list[F64], F64]:
    """The derivatives ``derivs`` of the local polynomial of ``y`` (S, n) on the time axis
    ``t`` (S,), ``w`` (odd, <= S) samples per fit; and the centre weights h0 (S,)."""
    if _uniform(t):
        return _savgol(t, y, w, polyorder, derivs)
    s, n = y.shape
    scale = float(t[min(s - 1, w - 1)] - t[0]) / 2.0 or 1.0
    out = [np.empty_like(y) for _ in derivs]
    h0 = np.empty(s)
    step = max(1, _CHUNK_FLOATS // ((polyorder + 1) * (n + 2)))
    for a in range(0, s, step):
        centres = np.arange(a, min(s, a + step))
        coef, h0[centres] = _chunk(t, y, centres, w, polyorder, scale)
        for k, d in enumerate(derivs):
            out[k][centres] = coef[:, d, :] * (math.factorial(d) / scale**d)
    return out, h0
