"""The noise floor: the measurement noise estimated from the data alone, without a model.

* Rigidly linked points: the distance between two points measured in the same pose is the same
  in every pose; its spread is sqrt(2) sigma for isotropic noise.
* Repeats: poses with identical joint values; the spread of each point's coordinates.

The estimate is a :class:`NoiseFloor`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements
from zrp.jsonio import dict_from_dataclass

__all__ = ["CHI3_P95", "NOISE_METHODS", "NoiseFloor", "noise_floor"]

#: 95th percentile of |r| for isotropic Gaussian noise, in units of sigma (chi, 3 dof).
CHI3_P95 = 2.7954834829151074
NOISE_METHODS = ("rigid_links", "repeats", "given", "none")


@dataclass(frozen=True)
class NoiseFloor:
    """Measurement-noise estimate.

    Attributes:
        sigma: per-coordinate standard deviation (length unit), or None when the data allow no
            estimate.
        method: "rigid_links" (mutual distances of points measured in the same pose),
            "repeats" (poses measured more than once), "given" or "none".
        n_samples: number of distances or repeated coordinates it rests on.
        detail: per-pair or per-method numbers for the report.
    """

    sigma: float | None
    method: str
    n_samples: int = 0
    detail: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.method not in NOISE_METHODS:
            raise InputError(f"NoiseFloor.method: {self.method!r} not in {NOISE_METHODS}")
        if (self.sigma is None) != (self.method == "none"):
            raise InputError("NoiseFloor: sigma must be None exactly when method is 'none'")
        if self.sigma is not None and not (math.isfinite(self.sigma) and self.sigma >= 0):
            raise InputError(f"NoiseFloor.sigma: expected a finite value >= 0, got {self.sigma}")

    @property
    def rms(self) -> float | None:
        """Expected 3-D RMS of pure noise, sqrt(3) sigma."""
        return None if self.sigma is None else math.sqrt(3.0) * self.sigma

    @property
    def p95(self) -> float | None:
        return None if self.sigma is None else CHI3_P95 * self.sigma

    def to_dict(self) -> dict[str, Any]:
        return {"sigma": self.sigma, "rms": self.rms, "p95": self.p95,
                **dict_from_dataclass(self, exclude=("sigma",))}


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
