"""Fast time-segment cross-validation for the forward selection: the weighted, scaled normal
equations of every candidate column are accumulated once per training set (all segments but
one, less a guard), so that scoring a set of effects solves only a small P x P system per
segment (eq. F3: G_f = A_-f^T A_-f, c_f = A_-f^T b_-f; the same least squares as
:func:`zrp.gap.dynamics.fit.cross_validate`, bounds included).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

from zrp.arrays import F64
from zrp.gap.dynamics.effects import Effect
from zrp.gap.dynamics.fit import design, folds

__all__ = ["CVGram"]


def _bounded(g: F64, c: F64, lo: F64, hi: F64) -> F64:
    """argmin x^T G x - 2 c^T x within [lo, hi] (G >= 0)."""
    w, v = np.linalg.eigh(g)
    keep = w > 1e-12 * max(float(w.max()), 1e-300)
    r = np.sqrt(w[keep])[:, None] * v[:, keep].T
    rhs = (v[:, keep].T @ c) / np.sqrt(w[keep])
    x = v[:, keep] @ (rhs / np.sqrt(w[keep]))
    if np.all(x >= lo - 1e-12) and np.all(x <= hi + 1e-12):
        return x
    return lsq_linear(r, rhs, bounds=(lo, hi), method="bvls").x


class CVGram:
    """Normal equations of all candidate effects, per training set (eq. F3)."""

    def __init__(self, effects: list[Effect], b: F64, sigma: F64, k: int, guard: int) -> None:
        s, n = b.shape
        d = design(effects, s, n)
        aw = d.a / sigma[None, :, None]
        scale = np.sqrt(np.einsum("snp,snp->p", aw, aw))
        scale[scale == 0.0] = 1.0
        self.aw = aw / scale
        self.bw = b / sigma
        self.lower, self.upper = d.lower * scale, d.upper * scale
        self.scale, self.sigma = scale, sigma
        self.slices = dict(zip((e.key for e in effects), d.slices, strict=True))
        flat_a = self.aw.reshape(s * n, -1)
        g_all = flat_a.T @ flat_a
        c_all = flat_a.T @ self.bw.ravel()
        self.segments = folds(s, k)
        self.gram: list[tuple[F64, F64]] = []
        for seg in self.segments:
            out = slice(max(seg[0] - guard, 0), seg[-1] + guard + 1)
            a_out = self.aw[out].reshape(-1, flat_a.shape[1])
            self.gram.append((g_all - a_out.T @ a_out, c_all - a_out.T @ self.bw[out].ravel()))

    def columns(self, keys: list[str]) -> np.ndarray:
        return np.concatenate([np.arange(self.slices[k].start, self.slices[k].stop)
                               for k in keys]) if keys else np.zeros(0, dtype=int)

    def predict(self, keys: list[str]) -> F64:
        """Out-of-segment predictions of the torques (S, n) with the effects ``keys``."""
        idx = self.columns(keys)
        pred = np.zeros_like(self.bw)
        if idx.size == 0:
            return pred
        for seg, (g, c) in zip(self.segments, self.gram, strict=True):
            x = _bounded(g[np.ix_(idx, idx)], c[idx], self.lower[idx], self.upper[idx])
            pred[seg] = self.aw[seg][..., idx] @ x
        return pred * self.sigma
