"""The diagnosis's final model refitted with the measured orientations (full pose).

When the measurements carry ``qw..qz`` (a 6-DOF probe), :func:`zrp.gap.diagnose` refits its
final model (registration included) from positions and orientations together on the same
fitting poses, each block weighted by its own noise (:mod:`zrp.gap.fit.fullpose`, eqs. O1-O2),
and judges both estimates on the diagnosis's own withheld poses:

- effects only the orientations reveal are added by a score-test search on the fitting
  poses (:mod:`zrp.gap.search.posesearch`), each confirmed on the withheld orientations;
- orientation error before: the position-only final fit, with the probe rotation R_t0 that
  fits it best on the fitting poses (:func:`zrp.gap.fit.fullpose.probe_start`);
- orientation error after: the full-pose fit with its identified probe rotation R_t;
- the withheld position RMS of both (position-only: the final model refitted), and each
  parameter's standard error with and without orientations (normal theory of the weighted
  problem, the same formula for both).

The withheld poses never enter a fit; they confirm each group the orientation search adds
(as they choose between the search's model and the geometric baseline in the diagnosis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.fullpose import (
    FullPoseFit,
    fit_full_pose,
    orientation_residual,
    pose_rotations,
    probe_start,
)
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.problem import Problem
from zrp.gap.search.posesearch import OrientationStep, forward_search
from zrp.jsonio import dict_from_dataclass
from zrp.rotations import er_from_matrix, rotvec_from_er

__all__ = ["FullPoseResult", "ParameterPrecision", "refit_full_pose"]



@dataclass(frozen=True)
class ParameterPrecision:
    """One parameter's full-pose value and standard errors with and without orientations.

    Attributes:
        name, effect, unit: as in the diagnosis's parameter estimates.
        value: full-pose estimate (unit); std_position_only, std_full_pose: standard errors
            (unit) of the position-only and the full-pose fits.
    """

    name: str
    effect: str
    unit: str
    value: float
    std_position_only: float
    std_full_pose: float

    def __post_init__(self) -> None:
        if not (self.std_position_only >= 0 and self.std_full_pose >= 0):
            raise InputError(f"ParameterPrecision {self.name}: standard errors must be >= 0")

    @property
    def ratio(self) -> float:
        """Full-pose over position-only standard error (nan when the latter is 0)."""
        return (self.std_full_pose / self.std_position_only if self.std_position_only > 0
                else math.nan)

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self), "std_ratio": self.ratio}


@dataclass(frozen=True, eq=False)
class FullPoseResult:
    """What the measured orientations add to a diagnosis (module doc).

    Attributes:
        fit: the full-pose fit of the final model (its ``position``: the position-only refit).
        sigma_orientation: orientation noise per component used as weight (rad).
        sigma_orientation_given: it was given (False: estimated from the residuals).
        probe_rotation: R_t, probe frame in the hand frame, shape (3, 3).
        withheld_orientation_before, withheld_orientation_after: RMS rotation angle on the
            withheld poses of the position-only and the full-pose estimates (rad).
        withheld_rms_position_only, withheld_rms: 3-D position RMS on the withheld poses of
            the position-only and the full-pose estimates (length unit).
        parameters: the effect parameters' precision, with and without orientations.
        added: groups the orientations revealed (:mod:`zrp.gap.search.posesearch`), in order; the
            fit includes them, the position-only figures ("before") do not.
        withheld_orientation_nominal: the same RMS angle for the registration alone (the
            nominal model), rad; NaN when not computed.
        baseline_withheld: withheld (orientation RMS rad, position RMS length unit) of the
            complete geometric calibration refitted from positions and orientations, or None.
        withheld_orientation_final: the same RMS angle for the diagnosis's final model as it
            is (identified from positions and orientations when the search used them, with
            its own probe rotation), rad; NaN when not computed.
    """

    fit: FullPoseFit
    sigma_orientation: float
    sigma_orientation_given: bool
    probe_rotation: F64
    withheld_orientation_before: float
    withheld_orientation_after: float
    withheld_rms_position_only: float
    withheld_rms: float
    parameters: tuple[ParameterPrecision, ...]
    added: tuple[OrientationStep, ...] = ()
    withheld_orientation_nominal: float = float("nan")
    baseline_withheld: tuple[float, float] | None = None
    withheld_orientation_final: float = float("nan")

    def __post_init__(self) -> None:
        vals = (self.sigma_orientation, self.withheld_orientation_before,
                self.withheld_orientation_after, self.withheld_rms_position_only,
                self.withheld_rms)
        if not all(np.isfinite(v) and v >= 0 for v in vals):
            raise InputError(f"FullPoseResult: noise and RMS values must be finite and >= 0, "
                             f"got {vals}")
        if np.shape(self.probe_rotation) != (3, 3):
            raise InputError("FullPoseResult.probe_rotation: expected shape (3, 3)")

    @property
    def std_ratio_median(self) -> float:
        """Median over the effect parameters of full-pose / position-only std (nan if none)."""
        r = np.array([p.ratio for p in self.parameters], dtype=float)
        r = r[np.isfinite(r)]
        return float(np.median(r)) if r.size else math.nan

    @property
    def best(self) -> ParameterPrecision | None:
        """The effect parameter whose standard error shrinks most (None without any)."""
        ok = [p for p in self.parameters if np.isfinite(p.ratio)]
        return min(ok, key=lambda p: p.ratio) if ok else None

    def to_dict(self) -> dict[str, Any]:
        rt = np.asarray(self.probe_rotation)
        return {"sigma_orientation_rad": self.sigma_orientation,
                "sigma_orientation_source": ("given" if self.sigma_orientation_given
                                             else "estimated"),
                "sigma_position": self.fit.sigma_position,
                "probe_rotation": rt.tolist(),
                "probe_rotvec_rad": rotvec_from_er(er_from_matrix(rt)).tolist(),
                "withheld_orientation_rms_rad": {"position_only": self.withheld_orientation_before,
                                                 "full_pose": self.withheld_orientation_after},
                "withheld_rms": {"position_only": self.withheld_rms_position_only,
                                 "full_pose": self.withheld_rms},
                "withheld_orientation_rms_nominal_rad": self.withheld_orientation_nominal,
                "withheld_orientation_rms_final_model_rad": self.withheld_orientation_final,
                "baseline_full_pose_withheld": None if self.baseline_withheld is None else {
                    "orientation_rms_rad": self.baseline_withheld[0],
                    "rms": self.baseline_withheld[1]},
                "std_ratio_median": self.std_ratio_median,
                "added_by_orientation": [a.to_dict() for a in self.added],
                "parameters": [p.to_dict() for p in self.parameters]}


def _angle_rms(e: F64) -> float:
    return float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))


def _rms(prob: Problem, theta: F64) -> float:
    r = prob.residual(theta).reshape(-1, 3)
    return float(np.sqrt(np.mean(np.sum(r ** 2, axis=1))))


def refit_full_pose(ctx: Context, final: FitResult, fitting: NDArray[np.int64],
                    withheld: NDArray[np.int64], n_registration: int,
                    orientation_sigma: float | None = None, *,
                    candidates: dict[str, list[ParamSpec]] | None = None, alpha: float = 1e-3,
                    min_gain: float = 0.01, max_steps: int = 2,
                    nominal: FitResult | None = None,
                    baseline: FitResult | None = None) -> FullPoseResult:
    """Refit ``final``'s parameters with the measured orientations, add the effects only the
    orientations reveal (:mod:`zrp.gap.search.posesearch`) and judge the estimates on the withheld
    poses (module doc).

    Args:
        ctx: the data context (measurements with ``qw..qz``).
        final: the diagnosis's final fit (its specs are refitted; registration included).
        fitting, withheld: the diagnosis's pose split, shapes (Pf,), (Pw,).
        n_registration: number of leading registration parameters in ``final.specs``.
        orientation_sigma: orientation noise per component (rad); None: estimated.
        candidates: effect -> parameters the orientation search may add (None: no search).
        alpha, min_gain, max_steps: of the orientation search (the diagnosis's own).
        nominal: the registration fit, whose withheld orientation error is reported beside.
        baseline: the complete geometric calibration, refitted from positions and
            orientations and judged on the withheld poses too.

    Raises:
        InputError: no orientations, a non-positive ``orientation_sigma``.
    """
    meas_rot = pose_rotations(ctx)  # refuses data without orientations, naming the columns
    w = np.asarray(withheld, dtype=np.int64)

    def judge(fp: FullPoseFit) -> tuple[float, float]:
        prob = Problem(ctx, fp.specs, w, fp.position.base_rotation)
        e, _ = orientation_residual(prob, fp.theta, np.zeros(3), fp.probe_rotation, meas_rot[w])
        return _angle_rms(e), _rms(prob, fp.theta)

    def refit(specs: tuple[ParamSpec, ...]) -> tuple[FullPoseFit, float, float]:
        fp = fit_full_pose(ctx, specs, fitting, orientation_sigma=orientation_sigma)
        return (fp, *judge(fp))

    fp0, ori0, pos0 = refit(tuple(final.specs))
    fp, added = fp0, ()
    if candidates:
        fp, added = forward_search(ctx, fp0, candidates, fitting, meas_rot[fitting], refit,
                                   (ori0, pos0), alpha, min_gain, max_steps)
    start = fp0.position  # the diagnosis's final model, positions only
    before = _position_only_orientation(ctx, start, fitting, w, meas_rot)
    ori, pos_rms = judge(fp)
    pos = fp.position
    params = tuple(ParameterPrecision(s.name, s.effect, s.unit, float(fp.theta[i]),
                                      float(pos.stderr[i]), float(fp.stderr[i]))
                   for i, s in enumerate(fp.specs) if i >= n_registration
                   and np.isfinite(pos.stderr[i]) and np.isfinite(fp.stderr[i]))
    nom = (float("nan") if nominal is None
           else _position_only_orientation(ctx, nominal, fitting, w, meas_rot))
    base = None if baseline is None else judge(fit_full_pose(
        ctx, baseline.specs, fitting, orientation_sigma=orientation_sigma))
    prob0 = Problem(ctx, start.specs, w, start.base_rotation)
    return FullPoseResult(fp, fp.sigma_orientation, fp.sigma_orientation_given,
                          fp.probe_rotation, before, ori, _rms(prob0, start.theta), pos_rms,
                          params, added, nom, base,
                          _position_only_orientation(ctx, final, fitting, w, meas_rot))


def _position_only_orientation(ctx: Context, f: FitResult, fitting: NDArray[np.int64],
                               withheld: NDArray[np.int64], meas_rot: F64) -> float:
    """Withheld RMS orientation error (rad) of a fit: its own probe rotation when it was
    identified with the orientations, else (a position-only fit) the one that fits it best on
    the fitting poses (:func:`~zrp.gap.fit.fullpose.probe_start`)."""
    rt0 = f.probe_rotation if f.probe_rotation is not None else probe_start(
        Problem(ctx, f.specs, fitting, f.base_rotation), f.theta, meas_rot[fitting])
    prob = Problem(ctx, f.specs, withheld, f.base_rotation)
    e, _ = orientation_residual(prob, f.theta, np.zeros(3), rt0, meas_rot[withheld])
    return _angle_rms(e)
