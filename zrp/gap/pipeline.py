"""The sim-to-real gap diagnosis: where the gap lies, which effect causes it, how far it shrinks.

Entry point: :func:`diagnose` (in-process; the ``zrp diagnose`` command and the blind benchmark
call it). The method and the JSON schema are documented in docs/diagnosis.md.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError, ZRPWarning
from zrp.gap.data import DataWarning, Measurements
from zrp.gap.effects import (
    EFFECTS,
    Context,
    ParamSpec,
    effect_parameters,
    registration_parameters,
)
from zrp.gap.fit import (
    Aliased,
    FitResult,
    check_identifiable,
    cv_rms,
    f_test,
    fit,
    group_key,
    initial_registration,
    orthonormal_basis,
    point_errors,
    wald_groups,
)
from zrp.gap.problem import Problem
from zrp.model.manipulator import Manipulator
from zrp.units import G_STANDARD, metres_per_unit

__all__ = [
    "Candidate",
    "Diagnosis",
    "GapWarning",
    "Metrics",
    "NoiseFloor",
    "ParameterEstimate",
    "Step",
    "diagnose",
    "noise_floor",
    "split_poses",
]

F64 = NDArray[np.float64]
SCHEMA_VERSION = 1
MIN_POSES = 8
#: final withheld RMS above this multiple of the noise-floor RMS counts as unexplained.
UNEXPLAINED_RATIO = 1.5
#: candidates whose cross-validated RMS is within this fraction of the winner's are reported
#: as indistinguishable from it.
TIE_TOL = 0.01
#: 95th percentile of |r| for isotropic Gaussian noise, in units of sigma (chi, 3 dof).
CHI3_P95 = 2.7954834829151074
NOISE_METHODS = ("rigid_links", "repeats", "given", "none")


class GapWarning(ZRPWarning):
    """The diagnosis ran but something limits what it can say (aliasing, poor data...)."""


@dataclass(frozen=True)
class Metrics:
    """3-D position errors |r| of a set of measured points (length unit).

    Attributes:
        rms: sqrt(mean |r|^2).
        p95: 95th percentile of |r|.
        max: largest |r|.
        n_points: number of measured points.
    """

    rms: float
    p95: float
    max: float
    n_points: int

    def __post_init__(self) -> None:
        vals = (self.rms, self.p95, self.max)
        if self.n_points < 1 or not all(math.isfinite(v) and v >= 0 for v in vals):
            raise InputError(f"Metrics: expected finite non-negative errors over >= 1 point, "
                             f"got rms={self.rms}, p95={self.p95}, max={self.max}, "
                             f"n_points={self.n_points}")

    @classmethod
    def of(cls, residual: F64) -> Metrics:
        e = point_errors(residual)
        return cls(float(np.sqrt(np.mean(e**2))), float(np.percentile(e, 95)), float(e.max()),
                   int(e.size))

    def to_dict(self) -> dict[str, Any]:
        return {"rms": self.rms, "p95": self.p95, "max": self.max, "n_points": self.n_points}


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
        return {"sigma": self.sigma, "rms": self.rms, "p95": self.p95, "method": self.method,
                "n_samples": self.n_samples, "detail": self.detail}


@dataclass(frozen=True)
class ParameterEstimate:
    """An identified parameter with its 95 % confidence interval (normal approximation)."""

    name: str
    effect: str
    joint: int
    unit: str
    value: float
    stderr: float
    ci95: tuple[float, float]

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise InputError(f"ParameterEstimate {self.name}: value {self.value} is not finite")
        if not (self.stderr >= 0):
            raise InputError(f"ParameterEstimate {self.name}: stderr {self.stderr} < 0")

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "effect": self.effect, "joint": self.joint,
                "unit": self.unit, "value": self.value, "stderr": self.stderr,
                "ci95": list(self.ci95)}


@dataclass(frozen=True)
class Candidate:
    """One effect tried at one step of the greedy search.

    Attributes:
        effect: the effect.
        joints: joints (or body vectors for ``link_length``) whose parameters were significant.
        n_params: parameters kept after the significance pruning.
        cv_rms: cross-validated 3-D RMS on the fitting set (length unit); NaN if not fitted.
        bic_delta: BIC change against the current model (negative is better).
        p_value: F test of the improvement against the current model.
        significant: it passed all the tests for being added.
        note: why it was not tried or not significant.
    """

    effect: str
    joints: tuple[int, ...]
    n_params: int
    cv_rms: float
    bic_delta: float
    p_value: float
    significant: bool
    note: str = ""

    def __post_init__(self) -> None:
        if self.effect not in EFFECTS:
            raise InputError(f"Candidate.effect: {self.effect!r} not in {EFFECTS}")
        if not 0.0 <= self.p_value <= 1.0:
            raise InputError(f"Candidate {self.effect}: p_value {self.p_value} not in [0, 1]")

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.effect, "joints": list(self.joints), "n_params": self.n_params,
                "cv_rms": None if math.isnan(self.cv_rms) else self.cv_rms,
                "bic_delta": None if math.isnan(self.bic_delta) else self.bic_delta,
                "p_value": self.p_value, "significant": self.significant, "note": self.note}


@dataclass(frozen=True)
class Step:
    """One effect added to the model, with what it achieved on the withheld poses."""

    effect: str
    joints: tuple[int, ...]
    parameters: tuple[ParameterEstimate, ...]
    withheld: Metrics
    fitting: Metrics
    cv_rms: float
    p_value: float
    bic_delta: float
    candidates: tuple[Candidate, ...]
    aliased: tuple[Aliased, ...]
    geometric_overlap: float = math.nan
    ties: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.effect not in EFFECTS:
            raise InputError(f"Step.effect: {self.effect!r} not in {EFFECTS}")
        bad = [t for t in self.ties if t not in EFFECTS]
        if bad:
            raise InputError(f"Step.ties: {bad} not in {EFFECTS}")

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.effect, "joints": list(self.joints), "ties": list(self.ties),
                "geometric_overlap": (None if math.isnan(self.geometric_overlap)
                                      else self.geometric_overlap),
                "parameters": [p.to_dict() for p in self.parameters],
                "rms": self.withheld.rms, "p95": self.withheld.p95, "max": self.withheld.max,
                "withheld": self.withheld.to_dict(), "fitting": self.fitting.to_dict(),
                "cv_rms": self.cv_rms, "p_value": self.p_value, "bic_delta": self.bic_delta,
                "candidates": [c.to_dict() for c in self.candidates],
                "aliased": [_alias_dict(a) for a in self.aliased]}


def _alias_dict(a: Aliased) -> dict[str, Any]:
    return {"name": a.name, "effect": a.effect, "partners": list(a.partners),
            "fraction": a.fraction, "dropped": a.dropped}


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """The result of :func:`diagnose` (see docs/diagnosis.md for the JSON form).

    Attributes:
        model_name, length_unit: of the nominal model.
        nominal: withheld errors after registration only.
        nominal_fitting: fitting-set errors after registration only.
        registration: the registration parameters (base frame, tool offsets).
        steps: effects added, in order.
        final: withheld errors of the final model.
        noise_floor: the noise estimate.
        unexplained: True when the final withheld RMS exceeds UNEXPLAINED_RATIO x the noise
            floor RMS; None when there is no noise estimate.
        verdict: one paragraph in plain words.
        split: pose ids of the fitting and withheld sets and the CV folds.
        where: the "where" analysis (see :func:`where_analysis`).
        aliased: parameters that the data cannot tell apart (reported, never absorbed).
        warnings: messages of the warnings raised during the run.
        nominal_fit, final_fit: the fits (for plots and in-process use).
        withheld_residual_before, withheld_residual_after: shape (3 Rw,).
        context: the data context.
        withheld_poses, fitting_poses: pose indices, shapes (Pw,), (Pf,).
    """

    model_name: str
    length_unit: str
    nominal: Metrics
    nominal_fitting: Metrics
    registration: tuple[ParameterEstimate, ...]
    steps: tuple[Step, ...]
    final: Metrics
    noise_floor: NoiseFloor
    unexplained: bool | None
    verdict: str
    split: dict[str, Any]
    where: dict[str, Any]
    aliased: tuple[Aliased, ...]
    warnings: tuple[str, ...]
    nominal_fit: FitResult
    final_fit: FitResult
    withheld_residual_before: F64
    withheld_residual_after: F64
    context: Context
    fitting_poses: NDArray[np.int64]
    withheld_poses: NDArray[np.int64]
    settings: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not all(isinstance(st, Step) for st in self.steps):
            raise InputError("Diagnosis.steps: expected Step objects")
        if self.unexplained is not None and not isinstance(self.unexplained, bool):
            raise InputError(f"Diagnosis.unexplained: expected True, False or None, got "
                             f"{self.unexplained!r}")
        if np.intersect1d(self.fitting_poses, self.withheld_poses).size:
            raise InputError("Diagnosis: fitting and withheld poses overlap")

    @property
    def effects(self) -> tuple[str, ...]:
        """Effects found, in order ("none" alone when nothing helped)."""
        return tuple(s.effect for s in self.steps) or ("none",)

    @property
    def top_effect(self) -> str:
        """The first effect found, or "none"."""
        return self.effects[0]

    @property
    def shrink(self) -> float:
        """Final over nominal withheld RMS (1: no improvement)."""
        return self.final.rms / self.nominal.rms if self.nominal.rms > 0 else 1.0

    @property
    def final_parameters(self) -> tuple[ParameterEstimate, ...]:
        """All effect parameters of the final model, estimated jointly (after the backward
        pass), with 95 % intervals. The per-step values are each estimated without the effects
        added later, so these are the ones to use."""
        nreg = len(self.registration)
        return _estimates(self.final_fit, nreg)

    @property
    def final_joints(self) -> dict[str, tuple[int, ...]]:
        """Effect -> joints (body-vector indices for link_length) in the final model."""
        out: dict[str, set[int]] = {}
        for s in self.final_fit.specs[len(self.registration):]:
            out.setdefault(s.effect, set())
            if s.joint > 0:
                out[s.effect].add(s.joint)
        return {e: tuple(sorted(j)) for e, j in out.items()}

    def parameter(self, name: str) -> ParameterEstimate:
        """The final estimate of one parameter (registration or effect)."""
        for p in self.final_parameters + self.registration:
            if p.name == name:
                return p
        raise InputError(f"no identified parameter {name!r}; identified: "
                         f"{', '.join(p.name for p in self.final_parameters)}")

    def to_dict(self) -> dict[str, Any]:
        """The JSON document (schema in docs/diagnosis.md)."""
        nf = self.noise_floor
        return {
            "schema_version": SCHEMA_VERSION,
            "model": self.model_name,
            "length_unit": self.length_unit,
            "settings": self.settings,
            "nominal": {"rms": self.nominal.rms, "p95": self.nominal.p95,
                        "max": self.nominal.max, "n_points": self.nominal.n_points,
                        "fitting": self.nominal_fitting.to_dict()},
            "registration": [p.to_dict() for p in self.registration],
            "steps": [s.to_dict() for s in self.steps],
            "effects": list(self.effects),
            "final": {**self.final.to_dict(), "shrink": self.shrink,
                      "effects": [{"effect": e, "joints": list(j)}
                                  for e, j in self.final_joints.items()],
                      "parameters": [p.to_dict() for p in self.final_parameters],
                      "ratio_to_noise_floor": (None if nf.rms is None or nf.rms == 0
                                               else self.final.rms / nf.rms)},
            "noise_floor": nf.to_dict(),
            "unexplained": self.unexplained,
            "verdict": self.verdict,
            "split": self.split,
            "where": self.where,
            "aliased": [_alias_dict(a) for a in self.aliased],
            "warnings": list(self.warnings),
        }


# ---- split and noise floor ---------------------------------------------------------------

def split_poses(meas: Measurements, rng: np.random.Generator, withheld_fraction: float = 0.25,
                folds: int = 5) -> tuple[NDArray[np.int64], NDArray[np.int64],
                                         list[NDArray[np.int64]]]:
    """Seeded split by pose (repeats of a pose stay together).

    Returns:
        fitting pose indices, withheld pose indices, and the CV folds (a partition of the
        fitting poses).
    """
    if not 0.0 < withheld_fraction < 1.0:
        raise InputError(f"withheld_fraction: expected a value in (0, 1), got {withheld_fraction}")
    if folds < 2:
        raise InputError(f"folds: expected at least 2 cross-validation folds, got {folds}")
    groups = meas.repeat_groups()
    ng = int(groups.max()) + 1
    order = rng.permutation(ng)
    n_with = max(1, round(withheld_fraction * ng))
    if ng - n_with < 2:
        raise InputError(f"only {ng} distinct poses: too few to withhold any; measure at least "
                         f"{MIN_POSES} distinct poses")
    withheld_groups = set(order[:n_with].tolist())
    is_with = np.array([g in withheld_groups for g in groups])
    fitting = np.flatnonzero(~is_with)
    withheld = np.flatnonzero(is_with)
    fit_groups = order[n_with:]
    fold_of_group = {int(g): i % folds for i, g in enumerate(fit_groups)}
    fold_id = np.array([fold_of_group[int(groups[p])] for p in fitting])
    fold_list = [fitting[fold_id == f] for f in range(folds) if np.any(fold_id == f)]
    return fitting, withheld, fold_list


def noise_floor(meas: Measurements, poses: NDArray[np.int64] | None = None,
                sigma: float | None = None) -> NoiseFloor:
    """Estimate the per-coordinate noise sigma (length unit) without any robot model.

    * Rigidly linked points: the distance between two points measured in the same pose is
      the same in every pose; its spread is sqrt(2) sigma for isotropic noise.
    * Repeats: poses with identical joint values; the spread of each point's coordinates.
    Uses the rigid links when there are several points per pose, else repeats; ``sigma``
    overrides both (method "given").
    """
    if sigma is not None:
        if not (sigma > 0 and math.isfinite(sigma)):
            raise InputError(f"noise sigma: expected a positive number, got {sigma}")
        return NoiseFloor(float(sigma), "given", 0)
    P = len(meas.pose_ids)
    poses = np.arange(P) if poses is None else np.asarray(poses)
    M = len(meas.point_labels)
    pos = np.full((P, M, 3), np.nan)
    pos[meas.pose_index, meas.point_index] = meas.xyz
    pos = pos[poses]
    detail: dict[str, Any] = {}
    if M >= 2:
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
        if dof > 0:
            return NoiseFloor(math.sqrt(ss / dof / 2.0), "rigid_links", dof, detail)
    groups = meas.repeat_groups()[poses]
    ss = 0.0
    dof = 0
    for g in np.unique(groups):
        members = np.flatnonzero(groups == g)
        if members.size < 2:
            continue
        x = pos[members]
        for m in range(M):
            xm = x[:, m][np.all(np.isfinite(x[:, m]), axis=1)]
            if xm.shape[0] >= 2:
                ss += float(np.sum((xm - xm.mean(0)) ** 2))
                dof += 3 * (xm.shape[0] - 1)
    if dof > 0:
        return NoiseFloor(math.sqrt(ss / dof), "repeats", dof, detail)
    return NoiseFloor(None, "none", 0, detail)


# ---- where ---------------------------------------------------------------------------------

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


def where_analysis(ctx: Context, result: FitResult, max_components: int = 5) -> dict[str, Any]:
    """Where the residual of ``result`` lies (evaluated on its own, the fitting, poses).

    Returns a dict with ``per_point`` (RMS per point label), ``worst_poses``, ``joints``
    (per joint: R^2 of the residual explained by a smooth function of the joint angle, and
    binned RMS), ``order``/``time``/``temperature`` (R^2 against measurement order, t and temp),
    ``regions`` (RMS per workspace region), ``projection`` (share of the residual each joint's
    geometric parameters explain, after the registration) and ``components`` (the singular
    vectors of the identification Jacobian that carry most of the residual).
    """
    meas = ctx.meas
    rows = np.flatnonzero(np.isin(meas.pose_index, result.poses))
    r = result.residual.reshape(-1, 3)
    e = np.linalg.norm(r, axis=1)
    pose_of_row = meas.pose_index[rows]
    out: dict[str, Any] = {"evaluated_on": "fitting", "n_points": int(e.size)}
    out["per_point"] = {lab: float(np.sqrt(np.mean(e[meas.point_index[rows] == m] ** 2)))
                        for m, lab in enumerate(meas.point_labels)
                        if np.any(meas.point_index[rows] == m)}
    per_pose = {}
    for p in np.unique(pose_of_row):
        per_pose[meas.pose_ids[p]] = float(np.sqrt(np.mean(e[pose_of_row == p] ** 2)))
    worst = sorted(per_pose.items(), key=lambda kv: -kv[1])[:5]
    out["worst_poses"] = [{"pose": k, "rms": v} for k, v in worst]
    q = ctx.q[pose_of_row]
    joints = []
    for k in range(ctx.n):
        qk = q[:, k]
        feats = (np.column_stack([qk, qk**2]) if ctx.model.prismatic[k] else
                 np.column_stack([np.sin(qk), np.cos(qk), np.sin(2 * qk), np.cos(2 * qk)]))
        edges = np.quantile(qk, np.linspace(0, 1, 7))
        idx = np.clip(np.searchsorted(edges, qk, side="right") - 1, 0, 5)
        bins = [{"lo": float(edges[b]), "hi": float(edges[b + 1]),
                 "rms": float(np.sqrt(np.mean(e[idx == b] ** 2))) if np.any(idx == b) else None}
                for b in range(6)]
        joints.append({"joint": k + 1, "r2": _r2(feats, r) if np.ptp(qk) > 0 else 0.0,
                       "range": [float(qk.min()), float(qk.max())], "bins": bins})
    out["joints"] = joints
    order = np.arange(e.size, dtype=float)
    order = (order - order.mean()) / max(order.std(), 1.0)
    out["order"] = {"r2": _r2(np.column_stack([order, order**2, order**3]), r)}
    for name, key in (("t", "time"), ("temp", "temperature")):
        arr = getattr(meas, name)
        if arr is not None and np.ptp(arr[rows]) > 0:
            z = arr[rows]
            z = (z - z.mean()) / z.std()
            out[key] = {"r2": _r2(np.column_stack([z, z**2]), r)}
    fk = ctx.nominal_fk
    pe = fk.position[pose_of_row]
    rad = np.linalg.norm(pe[:, :2], axis=1)
    redges = np.quantile(rad, [0, 1 / 3, 2 / 3, 1])
    zmid = float(np.median(pe[:, 2]))
    regions = []
    for a in range(3):
        for up in (False, True):
            sel = ((rad >= redges[a]) & (rad <= redges[a + 1])
                   & ((pe[:, 2] > zmid) if up else (pe[:, 2] <= zmid)))
            if sel.any():
                regions.append({"radius": [float(redges[a]), float(redges[a + 1])],
                                "height": "upper" if up else "lower",
                                "rms": float(np.sqrt(np.mean(e[sel] ** 2))),
                                "n_points": int(sel.sum())})
    out["regions"] = regions
    M = len(meas.point_labels)
    if M >= 2:
        R = np.full((len(meas.pose_ids), M, 3), np.nan)
        R[pose_of_row, meas.point_index[rows]] = r
        full = np.all(np.isfinite(R.reshape(len(R), -1)), axis=1)
        if full.any():
            Rf = R[full]
            tot = float(np.sum(Rf**2))
            out["common_share"] = (float(M * np.sum(Rf.mean(axis=1) ** 2) / tot)
                                   if tot > 0 else 0.0)
    out.update(_projection(ctx, result, max_components))
    return out


def _projection(ctx: Context, result: FitResult, max_components: int) -> dict[str, Any]:
    geo: list[ParamSpec] = []
    for eff in ("joint_offset", "link_length", "axis_misalignment"):
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
    proj: list[dict[str, Any]] = []
    for k in range(1, ctx.n + 2):
        cols = [i for i, s in enumerate(keep) if s.joint == k]
        if not cols:
            continue
        Qk = orthonormal_basis(G[:, cols])
        share = float(np.sum((Qk.T @ rp) ** 2) / rr) if rr > 0 else 0.0
        proj.append({"joint": k, "share": share,
                     "parameters": [keep[i].name for i in cols]})
    comps = []
    total = 0.0
    if G.shape[1] and rr > 0:
        w, V = np.linalg.eigh(G.T @ G)
        keep_sv = w > w.max() * 1e-12
        w, V = w[keep_sv], V[:, keep_sv]
        sv = np.sqrt(w)
        c = (V.T @ (G.T @ rp)) / sv  # U^T r with U = G V / s
        total = float(np.sum(c**2) / rr)
        order = np.argsort(-(c**2))[:max_components]
        for i in order:
            load = V[:, i]
            top = np.argsort(-np.abs(load))[:3]
            comps.append({"share": float(c[i] ** 2 / rr), "singular_value": float(sv[i]),
                          "parameters": [{"name": keep[t].name, "loading": float(load[t])}
                                         for t in top]})
    return {"projection": proj, "components": comps, "geometric_share": total}


# ---- the diagnosis -------------------------------------------------------------------------

def _estimates(result: FitResult, first: int, last: int | None = None) -> tuple[
        ParameterEstimate, ...]:
    se = result.stderr
    out = []
    for i in range(first, len(result.specs) if last is None else last):
        s = result.specs[i]
        v = float(result.theta[i])
        h = 1.959963984540054 * float(se[i])
        out.append(ParameterEstimate(s.name, s.effect, s.joint, s.unit, v, float(se[i]),
                                     (v - h, v + h)))
    return tuple(out)


def _withheld(ctx: Context, result: FitResult, poses: NDArray[np.int64]) -> F64:
    return Problem(ctx, result.specs, poses, result.base_rotation).residual(result.theta)


def _fmt(x: float | None, unit: str) -> str:
    return "n/a" if x is None else f"{x:.4g} {unit}"


def diagnose(model: Manipulator, measurements: Measurements, *,
             gravity_torque: F64 | None = None,
             effects: Sequence[str] = EFFECTS,
             rng: np.random.Generator | None = None,
             seed: int = 0,
             withheld_fraction: float = 0.25,
             folds: int = 5,
             alpha: float = 1e-3,
             min_gain: float = 0.01,
             max_steps: int = 4,
             noise_sigma: float | None = None,
             harmonics: tuple[int, ...] = (1, 2),
             gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0),
             progress: bool = False) -> Diagnosis:
    """Diagnose the gap between ``model`` and ``measurements``.

    Args:
        model: the nominal robot model ("the sim").
        measurements: measured tool points (see :func:`zrp.gap.load_measurements`).
        gravity_torque: the torque gravity exerts on each joint in each pose (positive when
            it turns the joint positively; N m), shape (P, n), in the order of
            ``measurements.pose_ids`` (:func:`mjcf.gravity_torques` computes it from an MJCF
            file with the robot's inertias); without it ``joint_compliance`` identifies a
            lumped-mass model.
        effects: candidate effects (subset of :data:`zrp.gap.EFFECTS`).
        rng: random generator for the split (default ``np.random.default_rng(seed)``).
        withheld_fraction: share of the (distinct) poses withheld from fitting and selection.
        folds: cross-validation folds within the fitting poses (used for ranking).
        alpha: significance level of the F test that admits an effect; joint groups are kept
            when their Wald p-value is below alpha / (number of groups).
        min_gain: an effect must lower the cross-validated RMS by at least this fraction.
        max_steps: most effects added.
        noise_sigma: known per-coordinate instrument noise (length unit), overriding the
            estimate from the data.
        harmonics: harmonics of ``cyclic_error``.
        gravity_dir: gravity direction in the base frame (lumped-mass compliance model).
        progress: show a tqdm progress bar.

    Returns:
        the :class:`Diagnosis`.

    Raises:
        InputError: too few poses, units that do not fit the model, unidentifiable
            registration, unknown effect names.
    """
    from tqdm.auto import tqdm

    bad = [e for e in effects if e not in EFFECTS]
    if bad:
        raise InputError(f"effects: unknown {', '.join(bad)}; valid: {', '.join(EFFECTS)}")
    if measurements.n_joints != model.n:
        raise InputError(f"{measurements.source}: {measurements.n_joints} joint columns, but "
                         f"the model {model.name!r} has {model.n} joints")
    rng = np.random.default_rng(seed) if rng is None else rng
    caught: list[str] = []
    with warnings.catch_warnings(record=True) as wlist:
        warnings.simplefilter("always")
        result = _diagnose(model, measurements, gravity_torque, tuple(effects), rng,
                           withheld_fraction, folds, alpha, min_gain, max_steps, noise_sigma,
                           harmonics, gravity_dir, progress, tqdm)
    for w in wlist:
        caught.append(str(w.message))
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    object.__setattr__(result, "warnings", tuple(dict.fromkeys(caught)))
    return result


def _sequential_alias(J: F64, names: Sequence[str], fixed: int) -> list[tuple[int, str]]:
    """Columns (from index ``fixed`` on) that are combinations of the columns before them:
    (index, partners) pairs (Gram-Schmidt on normalised columns, tolerance ALIAS_TOL)."""
    from zrp.gap.fit import ALIAS_TOL

    norms = np.linalg.norm(J, axis=0)
    A = J / np.where(norms > 0, norms, 1.0)
    Q = orthonormal_basis(A[:, :fixed])
    accepted = list(range(fixed))
    out: list[tuple[int, str]] = []
    for i in range(fixed, J.shape[1]):
        c = A[:, i]
        r = c - Q @ (Q.T @ c)
        r = r - Q @ (Q.T @ r)
        f = float(np.linalg.norm(r))
        if norms[i] == 0 or f < ALIAS_TOL:
            corr = np.abs(A[:, accepted].T @ c) if accepted else np.zeros(0)
            partners = [names[accepted[o]] for o in np.argsort(-corr)[:3]
                        if corr[o] >= 0.5 * corr.max()] if corr.size else []
            out.append((i, "/".join(partners)))
            continue
        accepted.append(i)
        Q = np.column_stack([Q, r / f])
    return out


def _registration_identifiable(ctx: Context, specs: list[ParamSpec], poses: NDArray[np.int64],
                               theta0: F64, rb0: F64, rng: np.random.Generator
                               ) -> tuple[list[ParamSpec], F64]:
    """Drop registration parameters that no pose set could identify (e.g. the tool offsets
    along the common axis of a SCARA, which trade against the base translation), with a
    warning; raise when these data cannot identify one that richer poses would."""
    names = [s.name for s in specs]
    fixed = 6 if ctx.meas.frame == "instrument" else 0
    _, J = Problem(ctx, specs, poses, rb0).residual_and_jacobian(theta0)
    # the base frame itself must be identifiable
    base_bad = _sequential_alias(J[:, :fixed], names[:fixed], 0) if fixed else []
    data_bad = base_bad + _sequential_alias(J, names, fixed)
    if not data_bad:
        return specs, theta0
    ref_rng = np.random.default_rng(rng.integers(2**32))
    P, M, n = 200, len(ctx.meas.point_labels), ctx.n
    lim = np.where(ctx.model.prismatic[:, None], [[0.0, 0.3 * ctx.model.reach]], [[-2.5, 2.5]])
    qref = ref_rng.uniform(lim[:, 0], lim[:, 1], (P, n))
    ref = Context(ctx.model, Measurements.from_arrays(
        np.repeat(np.arange(P), M), np.repeat(qref, M, 0), np.zeros((P * M, 3)),
        point=np.tile(list(ctx.meas.point_labels), P), frame=ctx.meas.frame,
        source="reference poses"))
    _, Jr = Problem(ref, specs, np.arange(P), rb0).residual_and_jacobian(theta0)
    structural = {i for i, _ in _sequential_alias(Jr, names, fixed)}
    limited = [(i, p) for i, p in data_bad if i not in structural or i < fixed]
    if limited:
        what = ", ".join(f"{names[i]} ~ {p or 'nothing'}" for i, p in limited)
        raise InputError(
            f"{ctx.meas.source}: the registration is not identifiable from these poses "
            f"({what}); the joints must move enough to rotate the tool in several directions")
    drop = {i for i, _ in data_bad}
    warnings.warn(f"registration: {', '.join(names[i] for i in sorted(drop))} cannot be told "
                  "apart from the other registration parameters for this robot (structural); "
                  "fixed at 0 and carried by " + ", ".join(sorted({p for _, p in data_bad})),
                  GapWarning, stacklevel=4)
    keep = [i for i in range(len(specs)) if i not in drop]
    return [specs[i] for i in keep], theta0[keep]


def _with_gravity_side(ctx: Context, reg: FitResult, fitting: NDArray[np.int64], rb0: F64,
                       alpha: float) -> Context:
    """Without MJCF inertias, which side of its play a gravity-loaded joint rests against is
    taken from the sign of the gravity torque of a lumped-mass compliance fit (fitting poses
    only), for the joints where that fit is significant; elsewhere equal unit masses decide."""
    import dataclasses

    specs, _ = effect_parameters(ctx, "joint_compliance")
    keep, _ = check_identifiable(ctx, reg, specs)
    side = ctx.gravity_side_torque()
    if not keep:
        return ctx
    nreg = len(reg.specs)
    fc = fit(ctx, list(reg.specs) + keep, fitting,
             np.concatenate([reg.theta, np.zeros(len(keep))]), rb0)
    pv = wald_groups(fc, nreg)
    thr = alpha / max(len(pv), 1)
    tau = np.zeros_like(side)
    sig_joint = np.zeros(ctx.n, dtype=bool)
    for i, s in enumerate(keep):
        if pv[group_key(s)] < thr:
            assert s.basis is not None
            tau += fc.theta[nreg + i] * s.basis
            sig_joint[s.joint - 1] = True
    if not sig_joint.any():
        return ctx
    return dataclasses.replace(ctx, gravity_side=np.where(sig_joint, tau, side))


def _gain_function(Q: F64, rp: F64, Gk: F64, pose: NDArray[np.int64], S: int, tau_k: F64,
                   d_k: F64) -> Any:
    """Residual removed by one play parameter of joint k for switching torques F, with the
    columns projected off span(Q): gain(F) = (c.r)^2 / (|c|^2 - |Q^T c|^2) where the column
    c = sum over rows of G_k B_F(pose). Everything is reduced per pose first, so a candidate
    costs O(S q) instead of O(R q) (rp must already be orthogonal to Q).

    Args:
        Q: orthonormal columns (3R, q); rp: residual (3R,); Gk: dx/dq_k per row (R, 3);
        pose: pose of each row (R,) in 0..S-1; tau_k, d_k: torque and approach per pose (S,).
    """
    R = Gk.shape[0]
    q = Q.shape[1]
    QtG = np.einsum("rcq,rc->rq", Q.reshape(R, 3, q), Gk)
    M = np.zeros((S, q))
    np.add.at(M, pose, QtG)
    u = np.bincount(pose, weights=np.einsum("rc,rc->r", rp.reshape(R, 3), Gk), minlength=S)
    nv = np.bincount(pose, weights=np.einsum("rc,rc->r", Gk, Gk), minlength=S)

    def gains(grid: F64) -> F64:
        B = np.where(np.abs(tau_k)[:, None] > grid[None, :], np.sign(tau_k)[:, None],
                     -d_k[:, None])  # (S, m)
        den = nv @ B**2 - np.sum((M.T @ B) ** 2, axis=0)
        num = (u @ B) ** 2
        return np.where(den > 1e-12 * max(float(nv.sum()), 1e-300), num / np.where(
            den > 0, den, 1.0), 0.0)

    return gains


def _switch_bands(dists: tuple | None, mass: float = 0.99) -> list[list[float] | None]:
    """Per joint, the range of switching torques holding ``mass`` of the profile weight
    (None for joints modelled by the approach direction only)."""
    out: list[list[float] | None] = []
    for thr, w in dists or ():
        t = np.asarray(thr, dtype=float)
        if t.size == 1 and not np.isfinite(t[0]):
            out.append(None)
            continue
        order = np.argsort(t)
        t, cw = t[order], np.cumsum(np.asarray(w, dtype=float)[order])
        lo = t[np.searchsorted(cw, (1.0 - mass) / 2)]
        hi = t[min(np.searchsorted(cw, 1.0 - (1.0 - mass) / 2), t.size - 1)]
        out.append([float(lo), float(hi)])
    return out


PAYLOAD_GRID_KG = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0)


def _with_backlash_switch(ctx: Context, base: FitResult, fitting: NDArray[np.int64],
                          sweeps: int = 2, max_candidates: int = 40) -> Context:
    """Per joint, the gravity torque above which a joint with play rests on the loaded flank
    instead of lagging against its approach direction (Coulomb friction of the load holds it
    below). Chosen on the fitting poses by profiling on top of the current model ``base``,
    joint by joint with the other joints' play in the model (a few coordinate sweeps): for
    thresholds at 0, the data's |torque| values (at most ``max_candidates`` quantiles) and
    infinity, the play fit that removes the most residual wins; infinity (the plain
    approach-direction model) unless another threshold removes clearly more (by 25 sigma^2).
    With MJCF torques, an unknown payload at the tool (which shifts the torques) is profiled
    too, over :data:`PAYLOAD_GRID_KG`, kept when it removes clearly more (25 sigma^2)."""
    import dataclasses

    d = ctx.meas.approach_direction()[fitting]
    n = ctx.n
    unit = [ParamSpec(f"q{k + 1}.unit", "rad", "joint_offset", "dq", k + 1, 0,
                      np.eye(n)[k][None, :].repeat(len(ctx.q), 0)) for k in range(n)]
    prob = Problem(ctx, list(base.specs) + unit, fitting, base.base_rotation)
    r, J = prob.residual_and_jacobian(np.concatenate([base.theta, np.zeros(n)]))
    nb = len(base.specs)
    jn = np.linalg.norm(J[:, :nb], axis=0)
    Abase = J[:, :nb] / np.where(jn > 0, jn, 1.0)
    Qbase = orthonormal_basis(Abase)
    G = J[:, nb:].reshape(-1, 3, n)  # dx/dq_k per row
    pose = prob.row_pose
    s2 = base.rss / base.dof

    def select(tau: F64) -> tuple[F64, float, tuple]:
        """Thresholds per joint, the residual they remove together (length unit^2) and per
        joint the plausible thresholds with their weights."""

        def columns(k: int, grid: F64) -> F64:
            """Basis columns for thresholds ``grid`` (m,): shape (3R, m)."""
            B = np.where(np.abs(tau[:, k])[:, None] > grid[None, :],
                         np.sign(tau[:, k])[:, None], -d[:, k][:, None])  # (S, m)
            return (G[:, :, k][:, :, None] * B[pose][:, None, :]).reshape(-1, grid.size)

        grids: dict[int, F64] = {}
        for k in range(n):
            a = np.abs(tau[:, k])
            approach = bool(np.any(d[:, k] > 0) and np.any(d[:, k] < 0))
            if not (approach or np.any(a > 0)):
                continue
            qs = np.unique(a[a > 0])
            if qs.size > max_candidates:
                qs = np.unique(np.quantile(qs, np.linspace(0.0, 1.0, max_candidates)))
            grids[k] = np.array([np.inf, *qs.tolist(), 0.0]) if qs.size else np.array([np.inf])
        switch = np.full(n, np.inf)
        for _ in range(sweeps):
            changed = False
            for k, grid in grids.items():
                if grid.size == 1:
                    continue
                others = [columns(j, switch[j:j + 1])[:, 0] for j in grids if j != k]
                A = np.column_stack([Abase, *[c / max(np.linalg.norm(c), 1e-300)
                                              for c in others]])
                Q = orthonormal_basis(A)
                rp = r - Q @ (Q.T @ r)

                gains_of = _gain_function(Q, rp, G[:, :, k], pose, len(fitting),
                                          tau[:, k], d[:, k])

                gains = gains_of(grid)
                i = int(np.argmax(gains))
                best = float(grid[i]) if gains[i] > gains[0] + 25.0 * s2 else np.inf
                if np.isfinite(best) and best > 0:
                    # refine between the neighbouring grid values with every data value
                    # (grid: inf, ascending |torque| quantiles, 0)
                    a = np.unique(np.abs(tau[:, k]))
                    lo = grid[i - 1] if i - 1 >= 1 else 0.0
                    hi = grid[i + 1] if i + 1 <= grid.size - 2 else a.max()
                    fine = a[(a >= lo) & (a <= hi)]
                    if fine.size:
                        g2 = gains_of(fine)
                        j = int(np.argmax(g2))
                        if g2[j] >= gains[i]:
                            best = float(fine[j])
                    # |torque| <= best keeps the approach side: put the threshold half-way to
                    # the next larger |torque| of the data
                    above = a[a > best]
                    best = 0.5 * (best + above.min()) if above.size else best
                if best != switch[k]:
                    switch[k] = best
                    changed = True
            if not changed:
                break
        if not grids:
            return switch, 0.0, ()
        C = np.column_stack([columns(k, switch[k:k + 1])[:, 0] for k in grids])
        C = C - Qbase @ (Qbase.T @ C)
        cn = np.linalg.norm(C, axis=0)
        Qc = orthonormal_basis(C / np.where(cn > 0, cn, 1.0))
        rp = r - Qbase @ (Qbase.T @ r)
        total = float(np.sum((Qc.T @ rp) ** 2))
        # how sure is each threshold? profile-likelihood weights exp(-d(RSS) / 2 sigma^2) with
        # sigma^2 from the residual left after the play is modelled
        s2a = max((base.rss - total) / max(base.dof - len(grids), 1), 1e-30)
        dists: list[tuple[tuple[float, ...], tuple[float, ...]]] = []
        for k in range(n):
            if k not in grids or not np.isfinite(switch[k]):
                dists.append(((float(switch[k]),), (1.0,)))
                continue
            others = [columns(j, switch[j:j + 1])[:, 0] for j in grids if j != k]
            A = np.column_stack([Abase, *[c / max(np.linalg.norm(c), 1e-300) for c in others]])
            Q = orthonormal_basis(A)
            rpk = r - Q @ (Q.T @ r)
            a = np.unique(np.abs(tau[:, k]))
            a = a[a > 0]
            cand = np.array([*a.tolist(), 0.0, float(switch[k])])
            g = _gain_function(Q, rpk, G[:, :, k], pose, len(fitting), tau[:, k], d[:, k])(cand)
            w = np.exp(-(g.max() - g) / (2.0 * s2a))
            keep = w > 1e-6 * w.max()
            dists.append((tuple(cand[keep].tolist()), tuple((w[keep] / w[keep].sum()).tolist())))
        return switch, total, tuple(dists)

    tau0 = ctx.gravity_side_torque()[fitting]
    switch, gain, dists = select(tau0)
    payload = 0.0
    if ctx.gravity_torque is not None:
        h_ee = ctx.end_effector_arms()[fitting]
        to_m = metres_per_unit(ctx.model.length_unit, "model.length_unit")
        for m in PAYLOAD_GRID_KG[1:]:
            sw_m, g_m, d_m = select(tau0 + G_STANDARD * m * h_ee * to_m)
            if g_m > gain + 25.0 * s2:
                switch, gain, dists, payload = sw_m, g_m, d_m, m
    return dataclasses.replace(ctx, backlash_switch=tuple(float(v) for v in switch),
                               backlash_switch_weights=dists or None, payload_kg=payload)


def _check_units(ctx: Context, poses: NDArray[np.int64]) -> None:
    meas = ctx.meas
    rows = np.isin(meas.pose_index, poses)
    m = meas.xyz[rows]
    p = ctx.nominal_fk.position[meas.pose_index[rows]]
    sm = float(np.sqrt(np.mean(np.sum((m - m.mean(0)) ** 2, axis=1))))
    sp = float(np.sqrt(np.mean(np.sum((p - p.mean(0)) ** 2, axis=1))))
    unit = ctx.model.length_unit
    if sp <= 1e-9 * ctx.model.characteristic_length:
        raise InputError(f"{meas.source}: the end effector hardly moves between the poses "
                         f"(spread {sp:.3g} {unit}); the data cannot be registered (are the "
                         "joint values in degrees? then pass --deg)")
    ratio = sm / sp
    if not 1 / 3 < ratio < 3:
        k = math.log10(ratio) if ratio > 0 else 0.0
        hint = (f"; the positions look scaled by 1e{round(k):+03d} (e.g. m instead of mm)"
                if abs(k - round(k)) < 0.2 and abs(round(k)) >= 1 else "")
        raise InputError(
            f"{meas.source}: units do not fit: the measured points spread {sm:.4g} around "
            f"their centre but the model's end effector spreads {sp:.4g} {unit} over the same "
            f"poses (ratio {ratio:.3g}){hint}; x, y, z must be in {unit}, and q in rad (or deg "
            "with --deg)")


def _diagnose(model: Manipulator, meas: Measurements,
              gravity_torque: F64 | None, effects: tuple[str, ...], rng: np.random.Generator,
              withheld_fraction: float, n_folds: int, alpha: float, min_gain: float,
              max_steps: int, noise_sigma: float | None, harmonics: tuple[int, ...],
              gravity_dir: tuple[float, float, float], progress: bool,
              tqdm: Any) -> Diagnosis:
    P = len(meas.pose_ids)
    n_distinct = int(meas.repeat_groups().max()) + 1
    if P < MIN_POSES or n_distinct < MIN_POSES:
        raise InputError(f"{meas.source}: {P} pose(s), {n_distinct} distinct; the diagnosis "
                         f"needs at least {MIN_POSES} distinct poses (a few hundred for a "
                         "reliable answer)")
    if n_distinct < P:
        warnings.warn(f"{meas.source}: {P - n_distinct} pose(s) repeat the joint values of an "
                      "earlier pose; repeats are kept together in the split and used for the "
                      "noise floor", DataWarning, stacklevel=3)
    if n_distinct < 50:
        warnings.warn(f"{meas.source}: only {n_distinct} distinct poses; effects with many "
                      "parameters will be hard to identify", DataWarning, stacklevel=3)
    if gravity_torque is not None:
        gravity_torque = np.asarray(gravity_torque, dtype=float)
        if gravity_torque.shape != (P, model.n) or not np.all(np.isfinite(gravity_torque)):
            raise InputError(f"gravity_torque: expected finite values of shape ({P}, {model.n}) "
                             f"(poses x joints), got shape {gravity_torque.shape}")
    ctx = Context(model, meas, gravity_torque, gravity_dir, tuple(harmonics))
    fitting, withheld, folds = split_poses(meas, rng, withheld_fraction, n_folds)
    missing = [lab for m, lab in enumerate(meas.point_labels)
               if not np.any(meas.point_index[np.isin(meas.pose_index, fitting)] == m)]
    if missing:
        raise InputError(f"{meas.source}: point(s) {', '.join(missing)} appear only in withheld "
                         "poses; every point must be measured in several poses")
    _check_units(ctx, fitting)
    unit = model.length_unit

    # registration
    reg_specs = registration_parameters(ctx)
    theta0, rb0 = initial_registration(ctx, reg_specs, fitting)
    reg_specs, theta0 = _registration_identifiable(ctx, reg_specs, fitting, theta0, rb0, rng)
    reg = fit(ctx, reg_specs, fitting, theta0, rb0)
    if not np.all(np.isfinite(reg.stderr)):
        bad = [s.name for s, v in zip(reg.specs, reg.stderr, strict=False) if not np.isfinite(v)]
        raise InputError(f"{meas.source}: the registration is not identifiable from these poses "
                         f"({', '.join(bad)} undetermined); the joints must move enough to "
                         "rotate the tool in several directions")
    nominal_fit_metrics = Metrics.of(reg.residual)
    if nominal_fit_metrics.rms > 0.1 * model.characteristic_length:
        raise InputError(
            f"{meas.source}: after registration the model still misses the measurements by "
            f"{nominal_fit_metrics.rms:.4g} {unit} RMS "
            f"({100 * nominal_fit_metrics.rms / model.reach:.1f} % of the reach): the model, "
            "the joint order/signs or the units (--deg) do not match the data")
    if nominal_fit_metrics.rms > 0.02 * model.characteristic_length:
        warnings.warn(f"after registration the gap is {nominal_fit_metrics.rms:.4g} {unit} RMS, "
                      "more than 2 % of the reach: check the model, joint signs and units",
                      GapWarning, stacklevel=3)
    before = _withheld(ctx, reg, withheld)
    nominal = Metrics.of(before)
    floor = noise_floor(meas, fitting, noise_sigma)
    where = where_analysis(ctx, reg)

    if "backlash" in effects:
        if gravity_torque is None:
            ctx = _with_gravity_side(ctx, reg, fitting, rb0, alpha)
    # greedy search
    cache: dict[str, tuple[list[ParamSpec], str | None]] = {
        e: effect_parameters(ctx, e) for e in effects}
    where["identifiability"] = _survey(ctx, reg, cache, rng)
    current = reg
    current_cv = cv_rms(ctx, reg, folds)
    steps: list[Step] = []
    all_aliased: list[Aliased] = []
    used: set[str] = set()
    switch_now: tuple[float, ...] | None = None
    bands_now: tuple | None = None
    payload_now = 0.0
    bar = tqdm(total=max_steps * len(effects), desc="diagnose", disable=not progress,
               leave=False)
    for _ in range(max_steps):
        cands: list[tuple[Candidate, FitResult | None, list[Aliased]]] = []
        for eff in effects:
            bar.update(1)
            if eff in used:
                continue
            if eff == "backlash":  # which flank: profiled on top of the current model
                ctx_b = _with_backlash_switch(ctx, current, fitting)
                cache[eff] = effect_parameters(ctx_b, eff)
                switch_now = ctx_b.backlash_switch
                bands_now = ctx_b.backlash_switch_weights
                payload_now = ctx_b.payload_kg
            specs, why = cache[eff]
            if not specs:
                cands.append((Candidate(eff, (), 0, math.nan, math.nan, 1.0, False,
                                        f"not tried: {why}"), None, []))
                continue
            keep, aliased = check_identifiable(ctx, current, specs)
            if not keep:
                cands.append((Candidate(eff, (), 0, math.nan, math.nan, 1.0, False,
                                        "no parameter identifiable on top of the current "
                                        "model"), None, aliased))
                continue
            nb = len(current.specs)
            f1 = fit(ctx, list(current.specs) + keep, fitting,
                     np.concatenate([current.theta, np.zeros(len(keep))]), rb0)
            pv = wald_groups(f1, nb)
            thr = alpha / max(len(pv), 1)
            sig = {g for g, p in pv.items() if p < thr}
            kept = [s for s in keep if group_key(s) in sig]
            if not kept:
                cands.append((Candidate(eff, (), 0, cv_rms(ctx, f1, folds),
                                        f1.bic - current.bic, f_test(current, f1), False,
                                        "no joint significant"), None, aliased))
                continue
            if len(kept) < len(keep):
                idx = [nb + i for i, s in enumerate(keep) if group_key(s) in sig]
                f1 = fit(ctx, list(current.specs) + kept, fitting,
                         np.concatenate([f1.theta[:nb], f1.theta[idx]]), rb0)
            cv = cv_rms(ctx, f1, folds)
            pval = f_test(current, f1)
            dbic = f1.bic - current.bic
            joints = tuple(sorted({s.joint for s in kept if s.joint > 0}))
            ok = pval < alpha and dbic < 0 and cv < current_cv * (1.0 - min_gain)
            note = "" if ok else ("F test not significant" if pval >= alpha else
                                  "BIC does not improve" if dbic >= 0 else
                                  f"cross-validated RMS improves by less than {min_gain:.0%}")
            cands.append((Candidate(eff, joints, len(kept), cv, dbic, pval, ok, note), f1,
                          aliased))
        ranked = sorted(cands, key=lambda c: (not c[0].significant,
                                              math.inf if math.isnan(c[0].cv_rms)
                                              else c[0].cv_rms))
        best = ranked[0] if ranked else None
        if best is None or not best[0].significant or best[1] is None:
            if ranked:
                steps_cands = tuple(c[0] for c in ranked)
                where.setdefault("last_candidates", [c.to_dict() for c in steps_cands])
            break
        cand, f_new, aliased = best
        assert f_new is not None
        used.add(cand.effect)
        if cand.effect == "backlash" and switch_now is not None:
            where["backlash_switch"] = [None if not np.isfinite(v) else v for v in switch_now]
            where["backlash_switch_band"] = _switch_bands(bands_now)
            where["backlash_payload_kg"] = payload_now
        nb = len(current.specs)
        after = _withheld(ctx, f_new, withheld)
        weak_or_dropped = tuple(a for a in aliased)
        all_aliased += [a for a in aliased if a.name in {s.name for s in cache[cand.effect][0]}]
        overlap = (_geometric_overlap(ctx, current, f_new.residual - current.residual)
                   if cand.effect not in GEOMETRIC else math.nan)
        ties = tuple(c[0].effect for c in ranked[1:] if c[0].significant
                     and c[0].cv_rms <= cand.cv_rms * (1.0 + TIE_TOL))
        if ties:
            warnings.warn(f"step {len(steps) + 1}: {', '.join(ties)} fit(s) the data as well as "
                          f"{cand.effect} (cross-validated RMS within {TIE_TOL:.0%}); these "
                          "data cannot tell the effects apart", GapWarning, stacklevel=3)
        steps.append(Step(cand.effect, cand.joints, _estimates(f_new, nb), Metrics.of(after),
                          Metrics.of(f_new.residual), cand.cv_rms, cand.p_value, cand.bic_delta,
                          tuple(c[0] for c in ranked), weak_or_dropped, overlap, ties))
        current, current_cv = f_new, cand.cv_rms
    bar.close()
    # backward pass: joints that an effect picked up while another effect was still missing
    # are dropped when the final model no longer needs them
    nreg = len(reg.specs)
    pruned: list[str] = []
    while len(current.specs) > nreg:
        pv = wald_groups(current, nreg)
        thr = alpha / max(len(pv), 1)
        drop = {g for g, p in pv.items() if p >= thr}
        if not drop:
            break
        keep_idx = [i for i, s in enumerate(current.specs)
                    if i < nreg or group_key(s) not in drop]
        pruned += sorted(drop)
        current = fit(ctx, [current.specs[i] for i in keep_idx], fitting,
                      current.theta[keep_idx], rb0)
    if pruned:
        where["backward_pruned"] = pruned
    after = _withheld(ctx, current, withheld)
    final = Metrics.of(after)

    # aliasing of the effects found (reported) and of joint 1 / last joint vs registration
    for st in steps:
        dropped = [a for a in all_aliased if a.dropped and a.effect == st.effect]
        if dropped:
            pairs = "; ".join(f"{a.name} ~ {'/'.join(a.partners) or 'nothing (no effect)'}"
                              for a in dropped)
            warnings.warn(f"{st.effect}: {len(dropped)} parameter(s) cannot be told apart from "
                          f"others with these data and were not estimated separately: {pairs}",
                          GapWarning, stacklevel=3)
    unexplained: bool | None
    if floor.rms is None:
        unexplained = None
    else:
        unexplained = bool(final.rms > UNEXPLAINED_RATIO * floor.rms)
    where_final = where_analysis(ctx, current) if steps else where
    verdict = _verdict(steps, nominal, final, floor, unexplained, unit, where_final)
    if steps:
        where["after_final_model"] = {k: v for k, v in where_final.items()
                                      if k not in ("identifiability", "last_candidates",
                                                   "backward_pruned")}
    pid = meas.pose_ids
    split = {"seed_note": "split drawn from the rng passed to diagnose()",
             "withheld_fraction": withheld_fraction,
             "fitting": [pid[i] for i in fitting], "withheld": [pid[i] for i in withheld],
             "folds": [[pid[i] for i in f] for f in folds]}
    settings = {"effects": list(effects), "alpha": alpha, "min_gain": min_gain,
                "max_steps": max_steps, "folds": n_folds, "harmonics": list(harmonics),
                "gravity_dir": list(gravity_dir), "frame": meas.frame,
                "compliance_model": "mjcf" if gravity_torque is not None else "lumped_masses",
                "thermal_t_ref_degC": ctx.t_ref, "n_poses": P,
                "n_points": meas.n_rows, "point_labels": list(meas.point_labels)}
    return Diagnosis(model.name, unit, nominal, nominal_fit_metrics,
                     _estimates(reg, 0), tuple(steps), final, floor, unexplained, verdict,
                     split, where, tuple(all_aliased), (), reg, current, before, after, ctx,
                     fitting, withheld, settings)


def _survey(ctx: Context, reg: FitResult,
            cache: dict[str, tuple[list[ParamSpec], str | None]],
            rng: np.random.Generator) -> dict[str, Any]:
    """Which parameters of each effect these data cannot identify on top of the registration,
    and which of those a rich random pose set would identify (so the data, not the model
    structure, are to blame: a warning names them)."""
    meas = ctx.meas
    n = ctx.n
    # joints that (almost) do not move
    for k in range(n):
        rng_k = float(np.ptp(ctx.q[reg.poses, k]))
        small = 1e-3 if not ctx.model.prismatic[k] else 1e-3 * ctx.model.characteristic_length
        if rng_k < small:
            warnings.warn(f"{meas.source}: joint {k + 1} does not move in the fitting poses "
                          f"(range {rng_k:.3g}); its offset, scale and other parameters cannot "
                          "be told apart", GapWarning, stacklevel=4)
    # reference: same model, tool and frame, random poses over +-2.5 rad (seeded, own stream)
    ref_rng = np.random.default_rng(rng.integers(2**32))
    P = 200
    qref = ref_rng.uniform(-2.5, 2.5, (P, n))
    M = len(meas.point_labels)
    ref_meas = Measurements.from_arrays(np.repeat(np.arange(P), M), np.repeat(qref, M, 0),
                                        np.zeros((P * M, 3)),
                                        point=np.tile(list(meas.point_labels), P),
                                        frame=meas.frame,
                                        temp=None if meas.temp is None else
                                        np.repeat(ref_rng.uniform(15, 30, P), M),
                                        source="reference poses")
    ref_ctx = Context(ctx.model, ref_meas, None, ctx.gravity_dir, ctx.harmonics)
    ref_reg = FitResult(reg.specs, reg.theta, reg.cov, np.zeros(3 * P * M),
                        np.zeros((3 * P * M, len(reg.specs))), reg.base_rotation,
                        np.arange(P), True)
    out: dict[str, Any] = {}
    union: list[ParamSpec] = []
    ref_union: list[ParamSpec] = []
    for eff, (specs, _) in cache.items():
        if not specs:
            continue
        _, rep = check_identifiable(ctx, reg, specs)
        out[eff] = {"not_identifiable": [_alias_dict(a) for a in rep if a.dropped],
                    "weak": [_alias_dict(a) for a in rep if not a.dropped],
                    "limited_by_data": []}
        union += specs
        ref_union += effect_parameters(ref_ctx, eff)[0]
    # all effects together, on the data and on the rich reference poses
    _, rep = check_identifiable(ctx, reg, union)
    _, ref_rep = check_identifiable(ref_ctx, ref_reg, ref_union)
    structural = {a.name for a in ref_rep if a.dropped}
    by_effect: dict[str, list[str]] = {}
    for a in rep:
        if a.dropped and a.name not in structural:
            by_effect.setdefault(a.effect, []).append(
                f"{a.name} ~ {'/'.join(a.partners) or 'nothing'}")
            out[a.effect]["limited_by_data"].append(a.name)
    for eff, items in by_effect.items():
        warnings.warn(f"rank-deficient data: {'; '.join(items)} ({eff}) cannot be identified "
                      "from these poses although richer poses would identify them; move the "
                      "joints over wider ranges", GapWarning, stacklevel=4)
    return out


GEOMETRIC = ("joint_offset", "encoder_scale", "link_length", "axis_misalignment")


def _geometric_overlap(ctx: Context, current: FitResult, correction: F64) -> float:
    """Share of a step's correction (change of the predicted positions on the fitting poses,
    shape (3R,)) that the geometric effects together (offsets, scales, links, tilts) on top of
    the current model could reproduce: 1 means the step is indistinguishable from geometry
    over these poses, 0 that it is entirely non-geometric."""
    geo: list[ParamSpec] = []
    for eff in GEOMETRIC:
        geo += effect_parameters(ctx, eff)[0]
    have = {s.name for s in current.specs}
    keep, _ = check_identifiable(ctx, current, [g for g in geo if g.name not in have])
    prob = Problem(ctx, list(current.specs) + keep, current.poses, current.base_rotation)
    _, J = prob.residual_and_jacobian(np.concatenate([current.theta, np.zeros(len(keep))]))
    jn = np.linalg.norm(J, axis=0)
    Q = orthonormal_basis(J / np.where(jn > 0, jn, 1.0))
    cc = float(correction @ correction)
    if cc <= 0:
        return 0.0
    return float(np.sum((Q.T @ correction) ** 2) / cc)


def _remains(w: dict[str, Any], unit: str) -> str:
    """Plain words on the structure of what remains (from a where analysis)."""
    r2_joint = max((j["r2"] for j in w["joints"]), default=0.0)
    r2_other = max([w["order"]["r2"]] + [w[k]["r2"] for k in ("time", "temperature") if k in w])
    regions = w["regions"]
    inner = [g["rms"] for g in regions if g is regions[0] or g["radius"] == regions[0]["radius"]]
    outer = [g["rms"] for g in regions if g["radius"] == regions[-1]["radius"]]
    txt = []
    common = w.get("common_share")
    if common is not None:
        txt.append(f"{100 * common:.0f} % of what remains moves all points of a pose together")
    if r2_joint < 0.1 and r2_other < 0.1:
        txt.append(f"it depends on no single joint angle, the measurement order, time or "
                   f"temperature (R^2 <= {max(r2_joint, r2_other):.2f})")
    else:
        j = max(w["joints"], key=lambda j: j["r2"])
        txt.append(f"it still depends on q{j['joint']} (R^2 {j['r2']:.2f})"
                   if j["r2"] >= r2_other else
                   f"it still depends on measurement order/time/temperature (R^2 "
                   f"{r2_other:.2f})")
    if inner and outer:
        txt.append(f"RMS {np.mean(inner):.3g} {unit} in the inner and {np.mean(outer):.3g} "
                   f"{unit} in the outer third of the reach")
    out = "What remains: " + "; ".join(txt) + "."
    if common is not None and common > 0.8 and r2_joint < 0.1 and r2_other < 0.1:
        out += (" This behaves like a pose-to-pose positioning error of the robot that no "
                "model correction of the joint angles or geometry reproduces (e.g. poor "
                "repeatability or settling); measuring repeated poses would tell the robot's "
                "own floor, which the rigid-link estimate (instrument noise only) does not.")
    return out


def _verdict(steps: list[Step], nominal: Metrics, final: Metrics, floor: NoiseFloor,
             unexplained: bool | None, unit: str, where_final: dict[str, Any] | None = None
             ) -> str:
    parts = []
    if steps:
        names = ", ".join(f"{s.effect} (joints {', '.join(map(str, s.joints)) or '-'})"
                          for s in steps)
        parts.append(f"Effects found, in order: {names}.")
        for i, s in enumerate(steps, 1):
            if s.ties:
                parts.append(f"At step {i} {', '.join(s.ties)} explain(s) the data equally well; "
                             f"the data cannot tell {'them' if len(s.ties) > 1 else 'it'} apart "
                             f"from {s.effect}.")
    else:
        parts.append("No effect in the library improves the model significantly (none).")
    parts.append(f"Withheld RMS {nominal.rms:.4g} {unit} after registration, "
                 f"{final.rms:.4g} {unit} after correction "
                 f"({100 * (1 - final.rms / nominal.rms) if nominal.rms > 0 else 0:.0f} % "
                 "smaller).")
    if floor.rms is None:
        parts.append("The data allow no noise-floor estimate (one point per pose and no "
                     "repeats), so whether a gap remains cannot be judged.")
    else:
        ratio = final.rms / floor.rms if floor.rms > 0 else math.inf
        parts.append(f"Noise floor {_fmt(floor.rms, unit)} RMS ({floor.method}); the final "
                     f"error is {ratio:.2g}x the floor.")
        if unexplained:
            parts.append(f"A gap of {final.rms:.4g} {unit} RMS remains that no effect in the "
                         "library explains.")
            if where_final is not None:
                parts.append(_remains(where_final, unit))
        else:
            parts.append("What remains is at the noise floor.")
    return " ".join(parts)
