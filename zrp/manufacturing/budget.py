"""The first-order error budget of given tolerances along a trajectory.

From the identification Jacobian (:func:`zrp.kinematics.identification.parameter_jacobian`):
the worst case over the tolerance box (:func:`worst_case_bound`), each parameter's share of the
deviation variance (:func:`contributions`, ranked) and both together with an optional Monte
Carlo comparison (:func:`tolerance_report`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q
from zrp.kinematics.identification import parameter_jacobian
from zrp.manufacturing.tolerance import Tolerances
from zrp.model.manipulator import Manipulator

__all__ = ["Contribution", "MonteCarloMaxima", "contributions", "tolerance_report",
           "worst_case_bound"]



class MonteCarloMaxima(Protocol):
    """What :func:`tolerance_report` reads of a Monte Carlo: its distribution and the largest
    per-robot maxima. Both the gathered
    :class:`~zrp.manufacturing.population.MonteCarloResult` and the reduced
    :class:`~zrp.manufacturing.reduction.MonteCarloSummary` have them; the reduction's
    histogram edges come from :func:`worst_case_bound`, so this module names neither type
    (the imports go one way: reduction -> budget)."""

    @property
    def distribution(self) -> str: ...

    def maxima(self) -> tuple[float, float]: ...


def worst_case_bound(jac: ArrayLike, tolerances: ArrayLike) -> tuple[F64, F64]:
    """First-order worst case over the tolerance box |dx_i| <= tol_i, per trajectory point.

    For each point, ``|J_p dx| <= sqrt(sum_a (sum_i |J_{a,i}| tol_i)^2)`` (rows a = x, y, z),
    and the same for the rotation rows. The bound is attained when one corner of the box
    aligns every component; it is exact for a single parameter.

    Args:
        jac: identification Jacobian, shape (..., 6, P).
        tolerances: half-widths tol_i >= 0 in parameter units, shape (P,).

    Returns:
        bound on delta_p (length unit) and on the error angle (rad), each shape (...).
    """
    jac = np.asarray(jac, dtype=float)
    tol = np.asarray(tolerances, dtype=float)
    if tol.shape != jac.shape[-1:]:
        raise InputError(f"tolerances: expected shape ({jac.shape[-1]},), got {tol.shape}")
    comp = np.abs(jac) @ tol  # (..., 6)
    return (np.linalg.norm(comp[..., 3:6], axis=-1), np.linalg.norm(comp[..., 0:3], axis=-1))


@dataclass(frozen=True, eq=False)
class Contribution:
    """Ranked contributions of each parameter along a trajectory (first order).

    Attributes:
        names: parameter names, ranked by ``share_p`` (largest first), P entries.
        tolerance: half-width tol_i (parameter unit), shape (P,).
        sens_p_max: max_t ||d p / d x_i|| (length unit per parameter unit), shape (P,).
        sens_r_max: max_t ||d rot / d x_i|| (rad per parameter unit), shape (P,).
        worst_p: sens_p_max * tol_i, the largest first-order delta_p it causes alone, (P,).
        worst_r: sens_r_max * tol_i (rad), shape (P,).
        share_p: share of the trajectory-mean variance of the position error, %, shape (P,).
        share_r: the same for the orientation error, %, shape (P,).
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    tolerance: F64
    sens_p_max: F64
    sens_r_max: F64
    worst_p: F64
    worst_r: F64
    share_p: F64
    share_r: F64

    def __post_init__(self) -> None:
        p = len(self.names)
        for name in ("tolerance", "sens_p_max", "sens_r_max", "worst_p", "worst_r", "share_p",
                     "share_r"):
            if np.shape(getattr(self, name)) != (p,):
                raise InputError(f"Contribution.{name}: expected shape ({p},), got "
                                 f"{np.shape(getattr(self, name))}")
        if len(self.units) != p:
            raise InputError(f"Contribution.units: expected {p} entries, got {len(self.units)}")

    def rows(self) -> list[dict[str, float | str]]:
        return [
            {"parameter": self.names[i], "unit": self.units[i],
             "tolerance": float(self.tolerance[i]), "sens_p_max": float(self.sens_p_max[i]),
             "sens_r_max": float(self.sens_r_max[i]), "worst_p": float(self.worst_p[i]),
             "worst_r_rad": float(self.worst_r[i]), "share_p_percent": float(self.share_p[i]),
             "share_r_percent": float(self.share_r[i])}
            for i in range(len(self.names))
        ]

    def markdown(self, length_unit: str = "mm", top: int | None = None) -> str:
        head = (f"| rank | parameter | tolerance | max dp/dx ({length_unit}/unit) | worst dp "
                f"({length_unit}) | worst angle (rad) | share of dp variance (%) | share of "
                f"angle variance (%) |\n|---:|---|---:|---:|---:|---:|---:|---:|")
        lines = [head]
        for r, row in enumerate(self.rows()[:top], start=1):
            lines.append(
                f"| {r} | {row['parameter']} | {row['tolerance']:.3g} {row['unit']} | "
                f"{row['sens_p_max']:.4g} | {row['worst_p']:.3e} | {row['worst_r_rad']:.3e} | "
                f"{row['share_p_percent']:.2f} | {row['share_r_percent']:.2f} |")
        return "\n".join(lines)


def contributions(jac: ArrayLike, tolerances: ArrayLike, names: tuple[str, ...],
                  units: tuple[str, ...], *, variance_factor: float = 1.0 / 3.0
                  ) -> Contribution:
    """Rank parameters by their first-order contribution along a trajectory.

    Args:
        jac: identification Jacobian along the trajectory, shape (T, 6, P).
        tolerances: half-widths, shape (P,).
        names, units: P parameter names and units (:func:`parameter_space`).
        variance_factor: variance of a parameter divided by tol^2: 1/3 for a uniform
            distribution on [-tol, tol], 1/9 for a normal one with tol = 3 sigma.

    The variance share of parameter i is ``mean_t ||J_i(t)||^2 var_i`` over the sum over i
    (parameters are independent, so first-order variances add).
    """
    jac = np.asarray(jac, dtype=float)
    tol = np.asarray(tolerances, dtype=float)
    if jac.ndim != 3 or jac.shape[1] != 6:
        raise InputError(f"jac: expected shape (T, 6, P), got {jac.shape}")
    if tol.shape != (jac.shape[2],) or len(names) != tol.size or len(units) != tol.size:
        raise InputError(f"tolerances/names/units: expected {jac.shape[2]} entries each")
    np_ = np.linalg.norm(jac[:, 3:6, :], axis=1)  # (T, P)
    nr = np.linalg.norm(jac[:, 0:3, :], axis=1)
    var = variance_factor * tol**2
    vp = np.mean(np_**2, axis=0) * var
    vr = np.mean(nr**2, axis=0) * var
    share_p = 100.0 * vp / vp.sum() if vp.sum() > 0 else np.zeros_like(vp)
    share_r = 100.0 * vr / vr.sum() if vr.sum() > 0 else np.zeros_like(vr)
    order = np.lexsort((-share_r, -share_p))
    sp, sr = np_.max(axis=0), nr.max(axis=0)
    return Contribution(
        names=tuple(names[i] for i in order), units=tuple(units[i] for i in order),
        tolerance=tol[order], sens_p_max=sp[order], sens_r_max=sr[order],
        worst_p=(sp * tol)[order], worst_r=(sr * tol)[order], share_p=share_p[order],
        share_r=share_r[order])


def tolerance_report(model: Manipulator, q: ArrayLike, tolerances: Tolerances,
                     mc: MonteCarloMaxima | None = None) -> dict[str, Any]:
    """First-order analysis of given tolerances: contributions, worst case, and (if ``mc`` is
    given, gathered or reduced on the workers) its comparison with the Monte Carlo maxima."""
    q = check_q(model, q)
    jac = parameter_jacobian(model, q, joint_offsets=tolerances.joint_offsets)
    dist = mc.distribution if mc is not None else "uniform"
    var_factor = 1.0 / 3.0 if dist == "uniform" else 1.0 / 9.0
    contrib = contributions(jac, tolerances.values, tolerances.names, tolerances.units,
                            variance_factor=var_factor)
    wc_p, wc_r = worst_case_bound(jac, tolerances.values)
    out: dict[str, Any] = {
        "worst_case_delta_p": float(wc_p.max()),
        "worst_case_angle_rad": float(wc_r.max()),
        "worst_case_t_index": int(np.argmax(wc_p)),
        "contribution": contrib,
    }
    if mc is not None:
        mc_p, mc_r = mc.maxima()
        out["mc_max_delta_p"] = mc_p
        out["mc_max_angle_rad"] = mc_r
        out["mc_over_worst_case_p"] = float(mc_p / wc_p.max()) if wc_p.max() > 0 else 0.0
    return out
