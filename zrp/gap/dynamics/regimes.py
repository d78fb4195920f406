"""Where the torques miss: per joint RMS of the residual in regimes of the motion (eq. W1):

* ``all``: every sample;
* ``low speed``: |qd_k| below 10 % of the joint's largest speed in the log;
* ``high speed``: |qd_k| above 50 % of it;
* ``reversal``: within half a filter window of a change of sign of qd_k (friction's jump);
* ``gravity-loaded``: |g_k(q)| above 50 % of the largest gravity torque of joint k in the log.

A regime with fewer than 20 samples on a joint is reported as None (cannot tell).
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64

__all__ = ["REGIMES", "regime_masks", "regime_rms"]

REGIMES = ("all", "low speed", "high speed", "reversal", "gravity-loaded")
MIN_SAMPLES = 20


def _near_reversal(qd: F64, half: int) -> np.ndarray:
    s = np.signbit(qd)
    flip = np.zeros_like(s)
    flip[1:] = s[1:] != s[:-1]
    out = np.zeros_like(s)
    for k in range(qd.shape[1]):
        idx = np.flatnonzero(flip[:, k])
        for i in idx:
            out[max(i - half, 0):i + half + 1, k] = True
    return out


def regime_masks(qd: F64, gravity: F64, half_window: int) -> dict[str, np.ndarray]:
    """Boolean masks (S, n) of each regime (eq. W1)."""
    vmax = np.abs(qd).max(0)
    gmax = np.abs(gravity).max(0)
    return {
        "all": np.ones(qd.shape, dtype=bool),
        "low speed": np.abs(qd) < 0.1 * vmax,
        "high speed": np.abs(qd) > 0.5 * vmax,
        "reversal": _near_reversal(qd, max(half_window, 1)),
        "gravity-loaded": np.abs(gravity) > 0.5 * gmax,
    }


def regime_rms(resid: F64, masks: dict[str, np.ndarray]) -> dict[str, list[float | None]]:
    """RMS of ``resid`` (S, n) per regime and joint (None: under 20 samples)."""
    out: dict[str, list[float | None]] = {}
    for name, mask in masks.items():
        row: list[float | None] = []
        for k in range(resid.shape[1]):
            r = resid[mask[:, k], k]
            row.append(float(np.sqrt(np.mean(r * r))) if r.size >= MIN_SAMPLES else None)
        out[name] = row
    return out
