"""The calibrated robot from full-pose data: the diagnosis's final model refitted with the
measured orientations (``qw..qz``), each block weighted by its own noise
(:mod:`zrp.gap.fit.fullpose`).

The diagnosis chooses the effects from the positions (its stepwise search is unchanged); when
the measurements carry orientations, the final model's parameters (registration included) are
then re-estimated from positions and orientations together on the same fitting poses, and the
withheld poses judge both estimates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.calibration.calibrated import CalibratedRobot
from zrp.errors import InputError
from zrp.gap.finalrecord import full_pose_fit_result
from zrp.gap.fit.fullpose import FullPoseFit, fit_full_pose, orientation_residual, pose_rotations
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.model.problem import Problem
from zrp.gap.results import Diagnosis

__all__ = ["FullPoseCalibration", "full_pose_calibration"]


@dataclass(frozen=True, eq=False)
class FullPoseCalibration:
    """What the orientations add to a calibration.

    Attributes:
        robot: the calibrated robot of the full-pose estimate.
        fit: the full-pose fit (its ``position`` member: the position-only refit).
        std_ratio: per effect parameter, full-pose std / position-only std (name -> ratio).
        withheld_rms_position_only, withheld_rms: 3-D RMS on the withheld poses of the
            position-only and the full-pose estimates (length unit).
        withheld_orientation_rms: RMS rotation angle on the withheld poses (rad), full pose.
    """

    robot: CalibratedRobot
    fit: FullPoseFit
    std_ratio: dict[str, float]
    withheld_rms_position_only: float
    withheld_rms: float
    withheld_orientation_rms: float

    def __post_init__(self) -> None:
        if not (self.withheld_rms >= 0 and self.withheld_rms_position_only >= 0):
            raise InputError("FullPoseCalibration: withheld RMS must be >= 0")

    def summary(self) -> dict[str, float]:
        r = np.array(list(self.std_ratio.values()))
        return {"sigma_orientation_rad": self.fit.sigma_orientation,
                "std_ratio_median": float(np.median(r)) if r.size else float("nan"),
                "std_ratio_min": float(r.min()) if r.size else float("nan"),
                "withheld_rms_position_only": self.withheld_rms_position_only,
                "withheld_rms": self.withheld_rms,
                "withheld_orientation_rms_rad": self.withheld_orientation_rms}


def _rms(prob: Problem, theta: np.ndarray) -> float:
    r = prob.residual(theta).reshape(-1, 3)
    return float(np.sqrt(np.mean(np.sum(r ** 2, axis=1))))


def full_pose_calibration(diag: Diagnosis, orientation_sigma: float | None = None
                          ) -> FullPoseCalibration:
    """Refit ``diag``'s final model with the measured orientations (module doc).

    Args:
        diag: a diagnosis of measurements with ``qw..qz``.
        orientation_sigma: orientation noise per component (rad); None: estimated.

    Raises:
        InputError: the measurements have no orientations.
    """
    ctx = diag.context
    pose_rotations(ctx)  # refuses data without orientations, naming the columns
    same = (diag.full_pose is not None
            and diag.settings.get("orientation_sigma_rad") == orientation_sigma)
    fp = (diag.full_pose.fit if same  # the diagnosis's own full-pose refit (zrp.gap.search.posefit)
          else fit_full_pose(ctx, diag.final_fit.specs, diag.fitting_poses,
                             orientation_sigma=orientation_sigma))
    specs = fp.specs  # with the groups the orientations revealed (zrp.gap.search.posesearch)
    rb0 = fp.position.base_rotation
    fit = (full_pose_fit_result(diag) if same else
           FitResult(tuple(specs), fp.theta, np.diag(fp.stderr ** 2), fp.position.residual,
                     fp.position.jac, rb0, np.asarray(diag.fitting_poses), True))
    robot = CalibratedRobot.from_diagnosis(diag, fit=fit)
    first = len(diag.registration)
    ratio = {s.name: float(fp.stderr[i] / fp.position.stderr[i])
             for i, s in enumerate(specs[first:], start=first)
             if np.isfinite(fp.position.stderr[i]) and fp.position.stderr[i] > 0}
    w = np.asarray(diag.withheld_poses)
    prob = Problem(ctx, specs, w, rb0)
    e, _ = orientation_residual(prob, fp.theta, np.zeros(3), fp.probe_rotation,
                                pose_rotations(ctx)[w])
    return FullPoseCalibration(robot, fp, ratio, _rms(prob, fp.position.theta),
                               _rms(prob, fp.theta),
                               float(np.sqrt(np.mean(np.sum(e ** 2, axis=1)))))
