"""Bounded weighted least squares of the effect parameters, its intervals and the
time-segment cross-validation that measures the withheld torque error.

Each joint's rows are weighted by 1 / sigma_k, its torque noise (eq. F1), so that the fit and
every RMS are in units of the noise. The parameters stay within their physical bounds
(:func:`scipy.optimize.lsq_linear`, columns scaled to unit norm first).

Intervals (eq. F2): cov = s^2 (A^T A)^-1 on the weighted, scaled columns with s^2 the
residual variance, inflated by (1 + rho) / (1 - rho) for the residuals' lag-one
autocorrelation rho (neighbouring samples of a filtered log are not independent). A parameter
at its bound keeps the interval of the unbounded problem (said in the result).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from zrp.arrays import F64
from zrp.gap.dynamics.effects import Effect

__all__ = ["Design", "Fit", "cross_validate", "design", "lag_one", "solve"]


@dataclass(frozen=True)
class Design:
    """The stacked columns of some effects: A (S, n, P), bounds (P,), each effect's slice."""

    a: F64
    lower: F64
    upper: F64
    slices: tuple[slice, ...]


@dataclass(frozen=True)
class Fit:
    """theta (P,), its covariance (P, P), the weighted residual's lag-one autocorrelation and
    which parameters sit on a bound."""

    theta: F64
    cov: F64
    rho: float
    at_bound: np.ndarray


def design(effects: list[Effect], s: int, n: int) -> Design:
    if not effects:
        return Design(np.zeros((s, n, 0)), np.zeros(0), np.zeros(0), ())
    a = np.concatenate([e.columns for e in effects], axis=-1)
    slices, start = [], 0
    for e in effects:
        p = e.columns.shape[-1]
        slices.append(slice(start, start + p))
        start += p
    return Design(a, np.concatenate([e.lower for e in effects]),
                  np.concatenate([e.upper for e in effects]), tuple(slices))


def _weighted(d: Design, b: F64, sigma: F64, rows: np.ndarray) -> tuple[F64, F64, F64]:
    aw = (d.a[rows] / sigma[:, None]).reshape(-1, d.a.shape[-1])
    bw = (b[rows] / sigma).ravel()
    scale = np.linalg.norm(aw, axis=0)
    scale[scale == 0.0] = 1.0
    return aw / scale, bw, scale


def _lsq(aw: F64, bw: F64, lo: F64, hi: F64) -> F64:
    if aw.shape[1] == 0:
        return np.zeros(0)
    if np.all(np.isinf(lo)) and np.all(np.isinf(hi)):
        return np.linalg.lstsq(aw, bw, rcond=1e-10)[0]
    res = lsq_linear(aw, bw, bounds=(lo, hi), lsmr_tol="auto", method="bvls")
    return res.x


def solve(d: Design, b: F64, sigma: F64, rows: np.ndarray | None = None,
          with_cov: bool = True) -> Fit:
    """Fit theta to b = tau - tau0 (S, n) on ``rows`` (all by default), eq. F1-F2."""
    rows = np.arange(b.shape[0]) if rows is None else rows
    if d.a.shape[-1] == 0:
        return Fit(np.zeros(0), np.zeros((0, 0)), 0.0, np.zeros(0, dtype=bool))
    aw, bw, scale = _weighted(d, b, sigma, rows)
    x = _lsq(aw, bw, d.lower * scale, d.upper * scale)
    theta = x / scale
    p = theta.size
    at_bound = (np.isclose(theta, d.lower) | np.isclose(theta, d.upper)) if p else np.zeros(0,
                                                                                         bool)
    if not with_cov or p == 0:
        return Fit(theta, np.zeros((p, p)), 0.0, at_bound)
    r = (bw - aw @ x).reshape(-1, b.shape[1])
    rho = lag_one(r)
    dof = max(bw.size - p, 1)
    s2 = float(r.ravel() @ r.ravel()) / dof
    cov_x = s2 * np.linalg.pinv(aw.T @ aw, rcond=1e-12) * (1 + rho) / (1 - rho)
    return Fit(theta, cov_x / np.outer(scale, scale), rho, at_bound)


def lag_one(r: F64) -> float:
    """The residual's lag-one autocorrelation (over time, pooled over joints), in [0, 0.99]."""
    if r.shape[0] < 3:
        return 0.0
    num = float(np.sum(r[1:] * r[:-1]))
    den = float(np.sum(r * r))
    return float(np.clip(num / den, 0.0, 0.99)) if den > 0 else 0.0


def folds(s: int, k: int) -> list[np.ndarray]:
    """k contiguous time segments of 0..s-1."""
    return [np.asarray(f) for f in np.array_split(np.arange(s), k)]


def cross_validate(d: Design, b: F64, sigma: F64, k: int, guard: int = 0) -> F64:
    """Out-of-segment predictions (S, n): each of k contiguous time segments predicted by the
    fit on the others (``guard`` samples on each side of the segment left out of that fit,
    so that the filter's window does not leak the withheld samples into the fit)."""
    s = b.shape[0]
    pred = np.zeros_like(b)
    for seg in folds(s, k):
        keep = np.ones(s, dtype=bool)
        keep[max(seg[0] - guard, 0):seg[-1] + guard + 1] = False
        fit = solve(d, b, sigma, np.flatnonzero(keep), with_cov=False)
        pred[seg] = d.a[seg] @ fit.theta
    return pred
