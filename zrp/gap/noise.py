"""The noise floor: the measurement noise estimated from the data alone, without a model.

* Rigidly linked points: the distance between two points measured in the same pose is the same
  in every pose; its spread is sqrt(2) sigma for isotropic noise.
* Repeats: poses with identical joint values; the spread of each point's coordinates.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.data import Measurements
from zrp.gap.metrics import NoiseFloor

__all__ = ["noise_floor"]

F64 = NDArray[np.float64]


def _positions(meas: Measurements, poses: NDArray[np.int64]) -> F64:
    """Measured positions per pose and point, NaN where not measured, shape (S, M, 3)."""
    pos = np.full((len(meas.pose_ids), len(meas.point_labels), 3), np.nan)
    pos[meas.pose_index, meas.point_index] = meas.xyz
    return pos[poses]


def _rigid_links(meas: Measurements, pos: F64) -> tuple[float, int, dict[str, Any]]:
    """Pooled sum of squares of the point-to-point distances about their means, its degrees
    of freedom, and per pair the numbers for the report."""
    M = pos.shape[1]
    detail: dict[str, Any] = {}
    ss = 0.0
    dof = 0
    for a in range(M):
        for b in range(a + 1, M):
            d = np.linalg.norm(pos[:, a] - pos[:, b], axis=1)
            d = d[np.isfinite(d)]
            if d.size < 3:
                continue
            ss += float(np.sum((d - d.mean()) ** 2))
            dof += d.size - 1
            mad = float(np.median(np.abs(d - np.median(d))))
            detail[f"{meas.point_labels[a]}-{meas.point_labels[b]}"] = {
                "mean_distance": float(d.mean()), "std": float(d.std(ddof=1)),
                "robust_std": 1.4826 * mad, "n": int(d.size)}
    return ss, dof, detail


def _repeats(groups: NDArray[np.int64], pos: F64) -> tuple[float, int]:
    """Pooled sum of squares of the coordinates of repeated poses about their means, and its
    degrees of freedom."""
    ss = 0.0
    dof = 0
    for g in np.unique(groups):
        members = np.flatnonzero(groups == g)
        if members.size < 2:
            continue
        x = pos[members]
        for m in range(pos.shape[1]):
            xm = x[:, m][np.all(np.isfinite(x[:, m]), axis=1)]
            if xm.shape[0] >= 2:
                ss += float(np.sum((xm - xm.mean(0)) ** 2))
                dof += 3 * (xm.shape[0] - 1)
    return ss, dof


def noise_floor(meas: Measurements, poses: NDArray[np.int64] | None = None,
                sigma: float | None = None) -> NoiseFloor:
    """Estimate the per-coordinate noise sigma (length unit) without any robot model.

    Uses the rigid links when there are several points per pose, else repeats (see the module
    docstring); ``sigma`` overrides both (method "given").
    """
    if sigma is not None:
        if not (sigma > 0 and math.isfinite(sigma)):
            raise InputError(f"noise sigma: expected a positive number, got {sigma}")
        return NoiseFloor(float(sigma), "given", 0)
    poses = np.arange(len(meas.pose_ids)) if poses is None else np.asarray(poses)
    pos = _positions(meas, poses)
    detail: dict[str, Any] = {}
    if len(meas.point_labels) >= 2:
        ss, dof, detail = _rigid_links(meas, pos)
        if dof > 0:
            return NoiseFloor(math.sqrt(ss / dof / 2.0), "rigid_links", dof, detail)
    ss, dof = _repeats(meas.repeat_groups()[poses], pos)
    if dof > 0:
        return NoiseFloor(math.sqrt(ss / dof), "repeats", dof, detail)
    return NoiseFloor(None, "none", 0, detail)
