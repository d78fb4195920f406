"""Uncertainty that holds when the model is imperfect: a pose-clustered sandwich covariance,
the parameter correlations, and physical plausibility checks of the final values.

The normal-theory covariance sigma^2 (J^T J)^-1 assumes the model is right and the errors
independent per coordinate. When a gap remains, the residuals of one pose are correlated (a
common shift of its points) and their size depends on the pose; the robust covariance

    C = (J^T J)^-1 (G/(G-1) sum_g J_g^T r_g r_g^T J_g) (J^T J)^-1           (sandwich, HC1)

sums the score of each pose g (its 3 M rows) before squaring, so it stays honest in both
cases (Huber 1967; White 1980; clustered: Liang & Zeger 1986).

The sandwich uses the fitted residuals, which are smaller than the errors, most of all at
poses of high leverage: with p parameters on G poses the hat matrix takes p/G of the error
variance on average (a 30-parameter model on 150 poses: 20 %), and a pose that alone pins a
parameter hides its own error. The pose-clustered jackknife (delete one pose, refit; "CR3",
MacKinnon & White 1985; Bell & McCaffrey 2002) corrects this. Linearised at the converged
solution, deleting pose g moves the estimate by (Woodbury)

    d_g = (J^T J)^-1 J_g^T (I - H_gg)^-1 r_g,   H_gg = J_g (J^T J)^-1 J_g^T      (J1)

(H_gg: the pose's 3 M x 3 M block of the hat matrix), and

    C_JK = (G-1)/G sum_g (d_g - mean d)(d_g - mean d)^T                          (J2)

which is one Gauss-Newton step of each leave-one-pose-out refit from the converged solution
(exact for a linear model), at the cost of G small solves. The reported standard error is the
largest of the jackknife, the sandwich and the normal-theory one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import special

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.sumzero import mapped_cov
from zrp.gap.model.context import Context

__all__ = [
    "STRONG_CORRELATION",
    "Correlations",
    "correlations",
    "interval_covariance",
    "jackknife_covariance",
    "plausibility",
    "robust_covariance",
    "robust_stderr",
    "simultaneous_z",
]

#: |correlation| above which a pair of parameters is named as strongly correlated.
STRONG_CORRELATION = 0.9

#: Typical magnitudes above which a value is implausible for an industrial arm (per unit).
_TYPICAL_MAX = {
    "joint_offset": 0.05,      # rad (~3 deg): an encoder zero error beyond it is a setup error
    "encoder_scale": 0.01,     # 1 %
    "backlash": 0.01,          # rad (~0.6 deg) of full play
    "cyclic_error": 0.005,     # rad amplitude
    "axis_misalignment": 0.02,  # rad
    "thermal_expansion": 5e-5,  # 1/degC
}


def _row_pose(ctx: Context, result: FitResult) -> NDArray[np.int64]:
    """Pose index of every measured point fitted, in the Problem's row order, shape (R,)."""
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, result.poses))
    return ctx.meas.pose_index[rows]


def robust_covariance(ctx: Context, result: FitResult) -> F64:
    """Pose-clustered sandwich covariance of ``result.theta``, shape (p, p) (see the module
    docstring; columns scaled for conditioning; inf where the normal-theory one is)."""
    J, r = result.free_jac, result.residual  # a constrained fit: its free coordinates
    p = J.shape[1]
    if p == 0:
        return np.zeros((0, 0))
    d, js, bread = _scaled_bread(J)
    pose = _row_pose(ctx, result)
    score = js.reshape(pose.size, 3, p) * r.reshape(pose.size, 3, 1)
    _, inv = np.unique(pose, return_inverse=True)
    G = int(inv.max()) + 1 if inv.size else 0
    per_pose = np.zeros((G, p))
    np.add.at(per_pose, inv, score.sum(axis=1))
    meat = per_pose.T @ per_pose * (G / max(G - 1, 1))
    return _unscaled(bread @ meat @ bread, d, result)


def _scaled_bread(J: F64) -> tuple[F64, F64, F64]:
    """Column norms d (p,), the scaled Jacobian J / d and the pseudo-inverse of its normal
    matrix (p, p) (eigenvalues below 1e-12 of the largest dropped)."""
    d = np.linalg.norm(J, axis=0)
    d = np.where(d > 0, d, 1.0)
    js = J / d
    w, v = np.linalg.eigh(js.T @ js)
    ok = w > max(w.max(), 1e-300) * 1e-12
    return d, js, (v[:, ok] / w[ok]) @ v[:, ok].T


def _unscaled(cov_scaled: F64, d: F64, result: FitResult) -> F64:
    """A covariance of the scaled parameters theta d (p, p) back in the units of theta, inf in
    the rows and columns where the normal-theory one (``result.cov``) is not finite."""
    cov = cov_scaled / np.outer(d, d)
    if result.tied is not None:  # back from the free coordinates (zrp.gap.fit.sumzero)
        cov = mapped_cov(result.tied, cov)
    bad = ~np.isfinite(np.diag(result.cov))
    cov[bad, :] = np.inf
    cov[:, bad] = np.inf
    return cov


def jackknife_covariance(ctx: Context, result: FitResult) -> F64:
    """Pose-clustered jackknife covariance of ``result.theta``, shape (p, p) (eqs J1-J2 of the
    module docstring; inf where the normal-theory one is, and for every parameter when a
    single pose alone determines one, leverage 1)."""
    J, r = result.free_jac, result.residual  # a constrained fit: its free coordinates
    p = J.shape[1]
    if p == 0:
        return np.zeros((0, 0))
    d, js, bread = _scaled_bread(J)
    pose = _row_pose(ctx, result)
    order = np.argsort(pose, kind="stable")
    _, start = np.unique(pose[order], return_index=True)
    rows3 = (3 * order[:, None] + np.arange(3)).ravel()  # coordinate rows, pose by pose
    bounds = np.append(3 * start, rows3.size)
    G = start.size
    deltas = np.zeros((G, p))
    for g in range(G):
        rows = rows3[bounds[g]:bounds[g + 1]]
        jg, rg = js[rows], r[rows]
        m = np.eye(rows.size) - jg @ bread @ jg.T  # I - H_gg
        try:
            u = np.linalg.solve(m, rg)
        except np.linalg.LinAlgError:
            u = np.full(rows.size, np.inf)
        if not np.all(np.isfinite(u)) or np.linalg.cond(m) > 1e12:
            return np.full((len(result.specs),) * 2, np.inf)
        deltas[g] = bread @ (jg.T @ u)
    dev = deltas - deltas.mean(axis=0)
    return _unscaled(dev.T @ dev * ((G - 1) / max(G, 1)), d, result)


def interval_covariance(ctx: Context, result: FitResult) -> F64:
    """The covariance behind the reported intervals, shape (p, p): the jackknife's
    correlations, scaled so that each variance is the largest of the jackknife, the sandwich
    and the normal-theory one (the module docstring says why)."""
    jk = jackknife_covariance(ctx, result)
    if np.any(np.isfinite(np.diag(result.cov)) & ~np.isfinite(np.diag(jk))):
        jk = robust_covariance(ctx, result)  # a pose of leverage 1: the sandwich instead
    sd = np.sqrt(np.clip(np.diag(jk), 0.0, None))
    se = np.maximum.reduce([sd, robust_stderr(ctx, result), result.stderr])
    fin = np.isfinite(sd) & np.isfinite(se) & (sd > 0)
    scale = np.where(fin, se / np.where(fin, sd, 1.0), 1.0)
    cov = jk * np.outer(scale, scale)
    cov[np.diag_indices_from(cov)] = se * se  # exactly se^2 (inf where not identified)
    return cov


def robust_stderr(ctx: Context, result: FitResult) -> F64:
    """Per parameter the larger of the robust (sandwich) and the normal-theory standard
    error, shape (p,)."""
    rob = np.sqrt(np.clip(np.diag(robust_covariance(ctx, result)), 0.0, None))
    return np.maximum(rob, result.stderr)


@dataclass(frozen=True)
class Correlations:
    """The correlation matrix of a set of parameters and its strongly correlated pairs.

    Attributes:
        names: the parameters (p).
        matrix: correlations, shape (p, p) (NaN where a variance is not finite).
        strong: pairs (a, b, rho) with |rho| >= :data:`STRONG_CORRELATION`, largest first.
    """

    names: tuple[str, ...]
    matrix: F64
    strong: tuple[tuple[str, str, float], ...]

    def __post_init__(self) -> None:
        if self.matrix.shape != (len(self.names), len(self.names)):
            raise InputError(f"Correlations: matrix shape {self.matrix.shape} does not match "
                             f"{len(self.names)} names")

    def to_dict(self) -> dict[str, Any]:
        m = [[None if not math.isfinite(x) else round(float(x), 4) for x in row]
             for row in self.matrix]
        return {"names": list(self.names), "matrix": m,
                "strong_pairs": [{"a": a, "b": b, "rho": rho} for a, b, rho in self.strong],
                "threshold": STRONG_CORRELATION}


def correlations(names: tuple[str, ...], cov: F64) -> Correlations:
    """Correlations of a covariance ``cov`` (p, p) and the pairs above the threshold."""
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        m = cov / np.outer(sd, sd)
    m[~np.isfinite(m)] = np.nan
    iu = np.triu_indices(len(names), 1)
    pairs = [(names[i], names[j], float(m[i, j])) for i, j in zip(*iu, strict=True)
             if np.isfinite(m[i, j]) and abs(m[i, j]) >= STRONG_CORRELATION]
    pairs.sort(key=lambda t: -abs(t[2]))
    return Correlations(tuple(names), m, tuple(pairs))


def plausibility(name: str, effect: str, value: float, stderr: float, unit: str) -> str | None:
    """Why a final value is physically implausible, or None.

    Negative backlash (a play is never negative) or negative compliance (a joint does not
    move against the load) by more than 2 standard errors; a magnitude beyond the typical range
    of an industrial arm (:data:`_TYPICAL_MAX`)."""
    neg = value < -2.0 * stderr
    if effect == "backlash" and neg:
        return (f"{name} = {value:.3g} {unit} is negative: a play cannot be; the approach-"
                "direction model does not describe this joint (or another effect mimics it)")
    if effect == "joint_compliance" and name.endswith(".compliance") and neg:
        return (f"{name} = {value:.3g} {unit} is negative: a joint does not deflect against "
                "its load; the gravity torques or another effect are wrong for this joint")
    lim = _TYPICAL_MAX.get(effect)
    if lim is not None and unit in ("rad", "1", "1/degC") and abs(value) > lim:
        return (f"{name} = {value:.3g} {unit} exceeds the typical range of an industrial arm "
                f"(|value| <= {lim:g} {unit}); check the model or the data")
    return None


def simultaneous_z(k: int, level: float = 0.95) -> float:
    """Half-width in standard errors of intervals that hold for all ``k`` parameters of an
    effect at once with probability ``level`` (Sidak: each at level**(1/k), exact for
    independent estimates and conservative for correlated ones, Sidak 1967):
    z = Phi^-1(1 - (1 - level**(1/k)) / 2). k = 1 gives 1.96; k = 4, 2.49."""
    if k < 1:
        raise InputError(f"simultaneous_z: k must be >= 1, got {k}")
    each = level ** (1.0 / k)
    return float(special.ndtri(1.0 - (1.0 - each) / 2.0))
