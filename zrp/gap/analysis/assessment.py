"""How far to trust the final model: the geometric baseline beside it, robust intervals,
correlations, plausibility, the registration in full, the joints the data leave
unidentifiable, and the evidence on what remains.

For what remains after the final model, each candidate explanation is weighed with the data's
own evidence (``Remainder``):

* **robot repeatability** - repeated poses (same joint values) measure it directly: the RMS of
  their scatter about their mean; without repeats it cannot be measured, and a pose-to-pose
  error far above the typical specified repeatability of an industrial arm
  (:data:`TYPICAL_REPEATABILITY_MM`) would conflict with the robot's specification;
* **drift** - R^2 of the residual against the measurement order and time;
* **instrument distance** - R^2 of the squared 3-D error against the distance from the
  instrument (range-dependent instrument error; instrument-frame data only);
* **per-pose rigid shift** - share of the residual common to all points of a pose (a shift of
  the whole tool: any error of the robot's position, or of the instrument's, looks so);
* **pose-dependent model error** - the multivariate, cross-validated test of
  :mod:`.structure` (all joint angles together, and time, temperature, load where logged);
  the largest R^2 against one joint angle stays as a hint beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.gap.analysis.baseline import GeometricBaseline
from zrp.gap.analysis.fallback import FinalChoice
from zrp.gap.analysis.notrun import NotRun
from zrp.gap.analysis.residual import ResidualModel
from zrp.gap.analysis.structure import Structure, remainder_structure
from zrp.gap.analysis.where import WhereAnalysis
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.registration import Registration
from zrp.gap.fit.uncertainty import Correlations
from zrp.gap.model.context import Context
from zrp.jsonio import dict_from_dataclass
from zrp.units import metres_per_unit

__all__ = ["TYPICAL_REPEATABILITY_MM", "Assessment", "Remainder", "compliance_units",
           "remainder_evidence"]

#: upper end of the specified pose repeatability (ISO 9283) of industrial arms up to ~50 kg
#: payload, mm (small arms such as the IRB 120: 0.01 mm; large ones 0.05-0.1 mm).
TYPICAL_REPEATABILITY_MM = 0.1
#: R^2 above which a dependence is said to be supported by the data.
SUPPORT_R2 = 0.1


@dataclass(frozen=True)
class Remainder:
    """The data's evidence on what remains after the final model.

    Attributes:
        rms: final residual RMS on the fitting poses (length unit).
        repeat_rms: 3-D RMS scatter of repeated poses, or None without repeats.
        n_repeat_groups: groups of repeated poses.
        order_r2, time_r2: R^2 against measurement order and time (None without ``t``).
        distance_r2: R^2 of |r|^2 against the distance from the instrument (None in the base
            frame).
        common_share: share common to the points of a pose (None with one point per pose).
        joint_r2: largest R^2 against one joint angle, and that joint.
        exceeds_spec: rms is above :data:`TYPICAL_REPEATABILITY_MM` (in the model's unit).
        structure: the multivariate test of :mod:`.structure` (None when it did not run).
        structure_not_run: why it did not run (None when it ran).
    """

    rms: float
    repeat_rms: float | None
    n_repeat_groups: int
    order_r2: float
    time_r2: float | None
    distance_r2: float | None
    common_share: float | None
    joint_r2: tuple[int, float]
    exceeds_spec: bool
    structure: Structure | None = None
    structure_not_run: str | None = None

    def findings(self) -> list[tuple[str, str, str]]:
        """(explanation, "supported" / "not supported" / "cannot tell", evidence) per
        candidate explanation of what remains."""
        out = []
        if self.repeat_rms is None:
            out.append(("robot repeatability (pose-to-pose scatter)", "cannot tell",
                        "no repeated poses; repeat some poses to measure it"
                        + ("; a scatter this large would conflict with the typical specified "
                           "repeatability of industrial arms" if self.exceeds_spec else "")))
        else:
            ok = self.repeat_rms >= 0.5 * self.rms
            out.append(("robot repeatability (pose-to-pose scatter)",
                        "supported" if ok else "not supported",
                        f"repeated poses scatter by {self.repeat_rms:.3g} RMS "
                        f"({self.n_repeat_groups} groups)"))
        drift = max(self.order_r2, self.time_r2 or 0.0)
        out.append(("drift over the measurement (thermal, instrument)",
                    "supported" if drift >= SUPPORT_R2 else "not supported",
                    f"R^2 against order/time {drift:.2f}"))
        if self.distance_r2 is None:
            out.append(("instrument error growing with distance", "cannot tell",
                        "data given in the base frame: the instrument's position is unknown"))
        else:
            out.append(("instrument error growing with distance",
                        "supported" if self.distance_r2 >= SUPPORT_R2 else "not supported",
                        f"R^2 of the squared error against the distance {self.distance_r2:.2f}"))
        out.append(self._pose_dependent())
        if self.common_share is not None:
            out.append(("a shift of the whole tool per pose (robot positioning or instrument)",
                        "supported" if self.common_share >= 0.8 else "not supported",
                        f"{100 * self.common_share:.0f} % of the residual is common to the "
                        "points of a pose; this does not separate robot from instrument"))
        return out

    def _pose_dependent(self) -> tuple[str, str, str]:
        j, r2 = self.joint_r2
        hint = f"largest R^2 against one joint angle {r2:.2f} (q{j})"
        s = self.structure
        if s is None:
            return ("a missing pose-dependent model term",
                    "supported" if r2 >= SUPPORT_R2 else "not supported", hint)
        on = f" on {', '.join(s.named)}" if s.named else ""
        return ("a missing pose-dependent model term",
                "supported" if s.structured else "not supported",
                f"cross-validated share predicted from the joint angles together "
                f"{100 * s.share:.0f} % (95 % {100 * s.interval[0]:.0f} to "
                f"{100 * s.interval[1]:.0f} %){on}; hint: {hint}")

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self, exclude=("joint_r2", "exceeds_spec", "structure")),
                "structure": None if self.structure is None else self.structure.to_dict(),
                "joint_r2": {"joint": self.joint_r2[0] or None, "r2": self.joint_r2[1]},
                "exceeds_typical_repeatability": self.exceeds_spec,
                "findings": [{"explanation": e, "status": s, "evidence": v}
                             for e, s, v in self.findings()]}


def _r2(x: F64, y: F64) -> float:
    if x.size < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return 0.0
    c = np.corrcoef(x, y)[0, 1]
    return float(c * c) if math.isfinite(c) else 0.0


def _repeat_scatter(ctx: Context, fit: FitResult) -> tuple[float | None, int]:
    """3-D RMS of the measured positions of repeated poses about their means."""
    meas = ctx.meas
    groups = meas.repeat_groups()
    ss, n, ng = 0.0, 0, 0
    for g in np.unique(groups[fit.poses]):
        members = np.flatnonzero(groups == g)
        if members.size < 2:
            continue
        ng += 1
        for m in range(len(meas.point_labels)):
            rows = np.flatnonzero(np.isin(meas.pose_index, members) & (meas.point_index == m))
            if rows.size >= 2:
                x = meas.xyz[rows]
                ss += float(np.sum((x - x.mean(0)) ** 2))
                n += rows.size - 1
    return (math.sqrt(ss / n) if n else None), ng


def remainder_evidence(ctx: Context, fit: FitResult, where: WhereAnalysis,
                       resolution: float = 0.0) -> Remainder:
    """Weigh the explanations of what the final model ``fit`` leaves (see the module
    docstring), on its fitting poses; the multivariate test only above 10x the fits'
    numerical ``resolution`` (below it the residual is rounding, not a remainder)."""
    meas = ctx.meas
    rows = np.flatnonzero(np.isin(meas.pose_index, fit.poses))
    e2 = np.sum(fit.residual.reshape(-1, 3) ** 2, axis=1)
    rms = float(np.sqrt(np.mean(e2)))
    dist_r2 = (_r2(np.linalg.norm(meas.xyz[rows], axis=1), e2)
               if meas.frame == "instrument" else None)
    rep, ng = _repeat_scatter(ctx, fit)
    jr = max(((j.joint, j.r2) for j in where.joints), key=lambda t: t[1], default=(0, 0.0))
    spec = TYPICAL_REPEATABILITY_MM / (1e3 * metres_per_unit(ctx.model.length_unit,
                                                             "model.length_unit"))
    structure, why = _structure(ctx, fit, rms, resolution)
    return Remainder(rms, rep, ng, where.order_r2, where.time_r2, dist_r2, where.common_share,
                     jr, bool(rms > spec), structure, why)


def _structure(ctx: Context, fit: FitResult, rms: float, resolution: float
               ) -> tuple[Structure | None, str | None]:
    """The multivariate test of what remains, or why it did not run."""
    if rms <= 10 * resolution:
        return None, (f"what remains ({rms:.3g} RMS) is within 10x the fits' numerical "
                      "resolution: rounding, not a remainder")
    try:
        return remainder_structure(ctx, fit), None
    except NotRun as exc:
        return None, str(exc)


def compliance_units(ctx: Context) -> dict[str, Any]:
    """In which unit ``joint_compliance`` is given, and why: rad/(N m) needs the masses of an
    MJCF (gravity torques); without one the lumped weights compliance x weight are identified
    in rad per length unit, and the masses cannot be separated from the compliance."""
    u = ctx.model.length_unit
    if ctx.gravity_torque is not None:
        return {"model": "mjcf", "unit": "rad/(N m)", "payload_unit": "rad/kg",
                "in_rad_per_newton_metre": True,
                "note": "compliances q{k}.compliance in rad/(N m) (prismatic joints: length "
                        "unit/(N m)) on the MJCF's gravity torques"}
    return {"model": "lumped_masses", "unit": f"rad/{u}", "payload_unit": f"rad/({u} kg)",
            "in_rad_per_newton_metre": False,
            "note": f"no MJCF supplied the masses, so compliance cannot be given in rad/(N m): "
                    f"each q{{k}}.w_{{p}} is the compliance times the weight of an unknown "
                    f"mass lumped at point p, in rad/{u} of moment arm (q{{k}}.w_load: per kg "
                    f"of the load column, rad/({u} kg)); one weight may be negative (a mass "
                    f"behind the joint), the weights of a joint sum to >= 0 (it deflects with "
                    f"its load in total); give the MJCF (--mjcf) for rad/(N m)"}


@dataclass(frozen=True, eq=False)
class Assessment:
    """How far to trust the final model (see the module docstring).

    Attributes:
        baseline: the complete geometric calibration and the non-geometric increment.
        frame: the full registration of the final model with robust intervals.
        correlations: of all parameters of the final model (robust covariance).
        stderr: robust standard errors of the final model's parameters, shape (p,).
        implausible: messages on physically implausible final values.
        unexcited: joints that move too little to carry a scale, cyclic error or backlash.
        remainder: the evidence on what remains.
        resolution: numerical resolution of the fits (length unit): below it nothing is
            resolved.
        compliance: the unit of ``joint_compliance`` and why (:func:`compliance_units`).
        choice: which model is final - the search's, the geometric calibration when the
            search's is worse on the withheld poses, or that calibration plus the search's
            non-geometric effects when it clearly beats both (:mod:`zrp.gap.analysis.fallback`).
        one_sided: joints whose MJCF gravity torque keeps one sign in every pose: a play that
            gravity holds on its loaded flank there shifts the joint by a constant, which these
            data cannot tell from its offset (empty without MJCF torques).
        residual_model: the learned residual term and its withheld test, when asked for
            (:mod:`zrp.gap.analysis.residual`).
        residual_model_not_run: why the learned term, when asked for, did not run.
    """

    baseline: GeometricBaseline
    frame: Registration
    correlations: Correlations
    stderr: F64
    implausible: tuple[str, ...]
    unexcited: tuple[int, ...]
    remainder: Remainder
    resolution: float
    choice: FinalChoice | None = None
    compliance: dict[str, Any] | None = None
    one_sided: tuple[int, ...] = ()
    residual_model: ResidualModel | None = None
    residual_model_not_run: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self, exclude=("stderr",), rename={
            "baseline": "geometric_baseline", "frame": "registration_full",
            "correlations": "correlation", "unexcited": "unexcited_joints",
            "choice": "final_model", "compliance": "compliance_units",
            "one_sided": "one_sided_gravity_joints"})
