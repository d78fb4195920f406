"""Where the gap lies: the structure of a fit's residual, without any effect model.

:func:`where_analysis` says how the residual spreads over the measured points, the poses, each
joint's angle, the measurement order, time, temperature and the workspace, and how much of it
each joint's geometric parameters (and the singular directions of the identification Jacobian)
could explain. The result is a frozen :class:`WhereAnalysis` whose ``to_dict()`` is the
"where" section of diagnosis.json.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.leastsq import FitResult, check_identifiable, orthonormal_basis
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem
from zrp.jsonio import dict_from_dataclass

__all__ = [
    "Component",
    "JointShare",
    "JointTrend",
    "Region",
    "WhereAnalysis",
    "where_analysis",
]

#: geometric effects whose parameters the projection uses.
PROJECTION_EFFECTS = ("joint_offset", "link_length", "axis_misalignment")
N_BINS = 6


def _rms(e: F64) -> float:
    return float(np.sqrt(np.mean(e**2)))


@dataclass(frozen=True)
class JointTrend:
    """How the residual depends on one joint's value.

    Attributes:
        joint: 1-based joint.
        r2: share of the residual explained by a smooth function of the joint value.
        range: smallest and largest value over the poses (rad or length unit).
        bins: (lo, hi, RMS or None for an empty bin) over six quantile bins.
    """

    joint: int
    r2: float
    range: tuple[float, float]
    bins: tuple[tuple[float, float, float | None], ...]

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self, exclude=("bins",)),
                "bins": [{"lo": lo, "hi": hi, "rms": rms} for lo, hi, rms in self.bins]}


@dataclass(frozen=True)
class Region:
    """RMS of the residual in one workspace region (horizontal radius band x upper/lower)."""

    radius: tuple[float, float]
    height: str
    rms: float
    n_points: int

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


@dataclass(frozen=True)
class JointShare:
    """Share of the residual that one joint's geometric parameters explain."""

    joint: int
    share: float
    parameters: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


@dataclass(frozen=True)
class Component:
    """A singular direction of the geometric identification Jacobian: its share of the
    residual, its singular value and its three largest parameter loadings (name, loading)."""

    share: float
    singular_value: float
    parameters: tuple[tuple[str, float], ...]

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self, exclude=("parameters",)),
                "parameters": [{"name": n, "loading": v} for n, v in self.parameters]}


@dataclass(frozen=True)
class WhereAnalysis:
    """Where the residual of a fit lies (evaluated on the fit's own poses).

    Attributes:
        evaluated_on: which poses ("fitting").
        n_points: measured points analysed.
        per_point: RMS per point label.
        worst_poses: the five poses with the largest RMS, (pose id, RMS).
        joints: per joint, the dependence on its value (:class:`JointTrend`).
        order_r2, time_r2, temperature_r2: R^2 against the measurement order, ``t`` and
            ``temp`` (None when the column is absent or constant).
        regions: RMS per workspace region.
        common_share: share of the residual energy common to all points of a pose (several
            points per pose only).
        projection: share each joint's geometric parameters explain, after the registration.
        components: the singular directions carrying most of the residual.
        geometric_share: share all geometric parameters together explain.
    """

    evaluated_on: str
    n_points: int
    per_point: Mapping[str, float]
    worst_poses: tuple[tuple[str, float], ...]
    joints: tuple[JointTrend, ...]
    order_r2: float
    time_r2: float | None
    temperature_r2: float | None
    regions: tuple[Region, ...]
    common_share: float | None
    projection: tuple[JointShare, ...]
    components: tuple[Component, ...]
    geometric_share: float

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "evaluated_on": self.evaluated_on, "n_points": self.n_points,
            "per_point": dict(self.per_point),
            "worst_poses": [{"pose": k, "rms": v} for k, v in self.worst_poses],
            "joints": [j.to_dict() for j in self.joints],
            "order": {"r2": self.order_r2}}
        if self.time_r2 is not None:
            out["time"] = {"r2": self.time_r2}
        if self.temperature_r2 is not None:
            out["temperature"] = {"r2": self.temperature_r2}
        out["regions"] = [r.to_dict() for r in self.regions]
        if self.common_share is not None:
            out["common_share"] = self.common_share
        out["projection"] = [p.to_dict() for p in self.projection]
        out["components"] = [c.to_dict() for c in self.components]
        out["geometric_share"] = self.geometric_share
        return out


def _r2(features: F64, y: F64) -> float:
    """Share of the variance of y (N, 3) explained by a linear model in features (N, f)."""
    X = np.column_stack([np.ones(len(y)), features])
    yc = y - y.mean(0)
    tss = float(np.sum(yc**2))
    if tss <= 0 or len(y) <= X.shape[1] + 1:
        return 0.0
    coef = np.linalg.lstsq(X, y, rcond=None)[0]
    rss = float(np.sum((y - X @ coef) ** 2))
    return max(0.0, 1.0 - rss / tss)


def _joint_trend(ctx: Context, k: int, q: F64, e: F64, r: F64) -> JointTrend:
    qk = q[:, k]
    feats = (np.column_stack([qk, qk**2]) if ctx.model.prismatic[k] else
             np.column_stack([np.sin(qk), np.cos(qk), np.sin(2 * qk), np.cos(2 * qk)]))
    edges = np.quantile(qk, np.linspace(0, 1, N_BINS + 1))
    idx = np.clip(np.searchsorted(edges, qk, side="right") - 1, 0, N_BINS - 1)
    bins = tuple((float(edges[b]), float(edges[b + 1]),
                  _rms(e[idx == b]) if np.any(idx == b) else None) for b in range(N_BINS))
    return JointTrend(k + 1, _r2(feats, r) if np.ptp(qk) > 0 else 0.0,
                      (float(qk.min()), float(qk.max())), bins)


def _scalar_r2(arr: F64 | None, rows: NDArray[np.int64], r: F64) -> float | None:
    """R^2 of the residual against a per-row column (quadratic), None if absent or constant."""
    if arr is None or not np.ptp(arr[rows]) > 0:
        return None
    z = arr[rows]
    z = (z - z.mean()) / z.std()
    return _r2(np.column_stack([z, z**2]), r)


def _regions(ctx: Context, pose_of_row: NDArray[np.int64], e: F64) -> tuple[Region, ...]:
    pe = ctx.nominal_fk.position[pose_of_row]
    rad = np.linalg.norm(pe[:, :2], axis=1)
    redges = np.quantile(rad, [0, 1 / 3, 2 / 3, 1])
    zmid = float(np.median(pe[:, 2]))
    regions = []
    for a in range(3):
        for up in (False, True):
            sel = ((rad >= redges[a]) & (rad <= redges[a + 1])
                   & ((pe[:, 2] > zmid) if up else (pe[:, 2] <= zmid)))
            if sel.any():
                regions.append(Region((float(redges[a]), float(redges[a + 1])),
                                      "upper" if up else "lower", _rms(e[sel]),
                                      int(sel.sum())))
    return tuple(regions)


def _common_share(ctx: Context, rows: NDArray[np.int64], pose_of_row: NDArray[np.int64],
                  r: F64) -> float | None:
    meas = ctx.meas
    M = len(meas.point_labels)
    if M < 2:
        return None
    R = np.full((len(meas.pose_ids), M, 3), np.nan)
    R[pose_of_row, meas.point_index[rows]] = r
    full = np.all(np.isfinite(R.reshape(len(R), -1)), axis=1)
    if not full.any():
        return None
    Rf = R[full]
    tot = float(np.sum(Rf**2))
    return float(M * np.sum(Rf.mean(axis=1) ** 2) / tot) if tot > 0 else 0.0


def where_analysis(ctx: Context, result: FitResult, max_components: int = 5) -> WhereAnalysis:
    """Where the residual of ``result`` lies (evaluated on its own, the fitting, poses).

    See :class:`WhereAnalysis` for what it holds; ``max_components`` singular directions at
    most are reported.
    """
    meas = ctx.meas
    rows = np.flatnonzero(np.isin(meas.pose_index, result.poses))
    r = result.residual.reshape(-1, 3)
    e = np.linalg.norm(r, axis=1)
    pose_of_row = meas.pose_index[rows]
    per_point = {lab: _rms(e[meas.point_index[rows] == m])
                 for m, lab in enumerate(meas.point_labels)
                 if np.any(meas.point_index[rows] == m)}
    per_pose = {meas.pose_ids[p]: _rms(e[pose_of_row == p]) for p in np.unique(pose_of_row)}
    worst = tuple(sorted(per_pose.items(), key=lambda kv: -kv[1])[:5])
    q = ctx.q[pose_of_row]
    joints = tuple(_joint_trend(ctx, k, q, e, r) for k in range(ctx.n))
    order = np.arange(e.size, dtype=float)
    order = (order - order.mean()) / max(order.std(), 1.0)
    projection, components, geometric_share = _projection(ctx, result, max_components)
    return WhereAnalysis(
        evaluated_on="fitting", n_points=int(e.size), per_point=per_point, worst_poses=worst,
        joints=joints, order_r2=_r2(np.column_stack([order, order**2, order**3]), r),
        time_r2=_scalar_r2(meas.t, rows, r), temperature_r2=_scalar_r2(meas.temp, rows, r),
        regions=_regions(ctx, pose_of_row, e),
        common_share=_common_share(ctx, rows, pose_of_row, r),
        projection=projection, components=components, geometric_share=geometric_share)


def _components(G: F64, rp: F64, rr: float, keep: list[ParamSpec], max_components: int
                ) -> tuple[tuple[Component, ...], float]:
    """The singular directions of G carrying most of rp, and the share all of them carry."""
    w, V = np.linalg.eigh(G.T @ G)
    keep_sv = w > w.max() * 1e-12
    w, V = w[keep_sv], V[:, keep_sv]
    sv = np.sqrt(w)
    c = (V.T @ (G.T @ rp)) / sv  # U^T r with U = G V / s
    total = float(np.sum(c**2) / rr)
    comps = []
    for i in np.argsort(-(c**2))[:max_components]:
        load = V[:, i]
        top = np.argsort(-np.abs(load))[:3]
        comps.append(Component(float(c[i] ** 2 / rr), float(sv[i]),
                               tuple((keep[t].name, float(load[t])) for t in top)))
    return tuple(comps), total


def _projection(ctx: Context, result: FitResult, max_components: int
                ) -> tuple[tuple[JointShare, ...], tuple[Component, ...], float]:
    """Per joint, the share of the residual its geometric parameters explain on top of the
    fit's own parameters; the leading singular directions; the share of all together."""
    geo: list[ParamSpec] = []
    for eff in PROJECTION_EFFECTS:
        geo += effect_parameters(ctx, eff)[0]
    keep, _ = check_identifiable(ctx, result, geo)
    prob = Problem(ctx, list(result.specs) + keep, result.poses, result.base_rotation)
    theta = np.concatenate([result.theta, np.zeros(len(keep))])
    r, J = prob.residual_and_jacobian(theta)
    nb = len(result.specs)
    jn = np.linalg.norm(J[:, :nb], axis=0)
    Qr = orthonormal_basis(J[:, :nb] / np.where(jn > 0, jn, 1.0))
    G = J[:, nb:] - Qr @ (Qr.T @ J[:, nb:])
    gn = np.linalg.norm(G, axis=0)
    G = G / np.where(gn > 0, gn, 1.0)
    rp = r - Qr @ (Qr.T @ r)
    rr = float(rp @ rp)
    proj: list[JointShare] = []
    for k in range(1, ctx.n + 2):
        cols = [i for i, s in enumerate(keep) if s.joint == k]
        if not cols:
            continue
        Qk = orthonormal_basis(G[:, cols])
        share = float(np.sum((Qk.T @ rp) ** 2) / rr) if rr > 0 else 0.0
        proj.append(JointShare(k, share, tuple(keep[i].name for i in cols)))
    comps: tuple[Component, ...] = ()
    total = 0.0
    if G.shape[1] and rr > 0:
        comps, total = _components(G, rp, rr, keep, max_components)
    return tuple(proj), comps, total
