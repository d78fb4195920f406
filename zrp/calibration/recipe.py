"""The one calibration recipe: diagnose -> the calibrated robot of the final model -> its
full-pose refit when the data carry orientations -> the conditions of the data
(:func:`calibrate`). The command line (``zrp calibrate``), the notebooks and the studies all
call it, so the same data build the same calibrated robot everywhere.

::

    from zrp.calibration import CalibrationOptions, calibrate
    result = calibrate(model, meas, options=CalibrationOptions(gravity_torque=tau))
    result.write("calibrated.toml", "compensation.json")
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from numpy.typing import ArrayLike

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.conditions import Conditions
from zrp.calibration.fullpose import FullPoseCalibration, full_pose_calibration
from zrp.calibration.learned import LearnedTerm
from zrp.calibration.storage import write_calibration
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements
from zrp.gap.model.choices import EFFECTS
from zrp.gap.model.domains import DEFAULT_MAX_TILT_RAD
from zrp.gap.pipeline import diagnose
from zrp.gap.results import Diagnosis
from zrp.model.manipulator import Manipulator

__all__ = ["Calibration", "CalibrationOptions", "calibrate"]


@dataclass(frozen=True, kw_only=True)
class CalibrationOptions:
    """How :func:`calibrate` diagnoses and what it records.

    Attributes:
        gravity_torque: MJCF gravity torques per pose and joint (N m), shape (P, n), or None
            (lumped-mass compliance).
        effects: candidate effects (default all, :data:`zrp.gap.EFFECTS`).
        seed: seed of the fitting/withheld split.
        max_steps: most effects added.
        noise_sigma: known noise per coordinate (length unit), or None (estimated).
        use_orientation: use measured orientations (qw..qz) when the data carry them: the
            calibrated robot is then the full-pose refit.
        orientation_sigma: orientation noise per component (rad), or None (estimated).
        widen: physical domains widened (domain key -> upper bound); ``axis_tilt`` is also
            the diagnosis's tilt domain.
        data_path: the data file (its name and SHA-256 are recorded in the conditions).
        data_angle_unit: "rad" or "deg", as the data file gives the joint values.
        instrument: the measuring instrument (recorded in the conditions).
        progress: show the diagnosis's progress on stderr.
        residual_model: also train the learned residual term on the joint angles
            (``zrp diagnose --residual-model``); when the diagnosis keeps it (it lowers the
            withheld error clearly) the calibrated robot carries it (``learned``,
            :mod:`zrp.calibration.learned`), unless the calibration is a full-pose refit
            (the term was trained on the position-only final model's residual).
    """

    gravity_torque: ArrayLike | None = None
    effects: Sequence[str] = EFFECTS
    seed: int = 0
    max_steps: int = 4
    noise_sigma: float | None = None
    use_orientation: bool = True
    orientation_sigma: float | None = None
    widen: Mapping[str, float] | None = None
    data_path: str | Path | None = None
    data_angle_unit: str = "rad"
    instrument: str | None = None
    progress: bool = False
    residual_model: bool = False

    @property
    def max_tilt_rad(self) -> float:
        return (self.widen or {}).get("axis_tilt", DEFAULT_MAX_TILT_RAD)


@dataclass(frozen=True)
class Calibration:
    """What :func:`calibrate` returns.

    Attributes:
        diagnosis: the diagnosis the calibration came from.
        robot: the calibrated robot (the full-pose refit's when ``full_pose``), with the data's
            conditions and the widened domains.
        full_pose: the full-pose calibration (measured orientations), or None.
        learned_note: why a kept learned residual term is not in the calibrated robot, or
            None.
    """

    diagnosis: Diagnosis
    robot: CalibratedRobot
    full_pose: FullPoseCalibration | None = None
    learned_note: str | None = None

    def write(self, model_path: str | Path, comp_path: str | Path, *,
              overwrite: bool = False) -> list[Path]:
        """Write calibrated.toml and compensation.json
        (:func:`~zrp.calibration.write_calibration`)."""
        return list(write_calibration(
            self.robot, model_path, comp_path, overwrite=overwrite,
            full_pose=None if self.full_pose is None else self.full_pose.fit))


def calibrate(model: Manipulator, measurements: Measurements, *,
              options: CalibrationOptions | None = None,
              diagnosis: Diagnosis | None = None) -> Calibration:
    """Calibrate ``model`` from ``measurements``: diagnose (or take ``diagnosis``, a diagnosis
    of these measurements), take the calibrated robot of its final model out
    (:meth:`CalibratedRobot.from_diagnosis`), refit it with the measured orientations when
    the diagnosis has a full-pose fit (:func:`~zrp.calibration.fullpose.
    full_pose_calibration`), and record the data's conditions and the widened domains.

    Raises:
        InputError: ``options`` is not a :class:`CalibrationOptions`, or ``diagnosis`` is not
            one of these measurements.
    """
    opt = CalibrationOptions() if options is None else options
    if not isinstance(opt, CalibrationOptions):
        raise InputError(f"options: expected CalibrationOptions, got {type(opt).__name__}")
    if diagnosis is None:
        diagnosis = diagnose(model, measurements, gravity_torque=opt.gravity_torque,
                             effects=tuple(opt.effects), seed=opt.seed,
                             max_steps=opt.max_steps, noise_sigma=opt.noise_sigma,
                             use_orientation=opt.use_orientation,
                             orientation_sigma=opt.orientation_sigma,
                             max_tilt_rad=opt.max_tilt_rad, progress=opt.progress,
                             residual_model=opt.residual_model)
    elif diagnosis.context.meas is not measurements and (
            diagnosis.context.meas.source != measurements.source):
        raise InputError(f"diagnosis: it diagnosed {diagnosis.context.meas.source}, not "
                         f"{measurements.source}")
    cal = CalibratedRobot.from_diagnosis(diagnosis)
    full = None
    if diagnosis.full_pose is not None:
        full = full_pose_calibration(diagnosis, opt.orientation_sigma)
        cal = full.robot
    cond = Conditions.from_measurements(
        measurements, model, data_path=opt.data_path, data_angle_unit=opt.data_angle_unit,
        instrument=opt.instrument)
    widen = None if opt.widen is None else dict(opt.widen)
    learned, note = _learned(diagnosis, full)
    return Calibration(diagnosis, dataclasses.replace(cal, widen=widen, conditions=cond,
                                                      learned=learned), full, note)


def _learned(diag: Diagnosis, full: FullPoseCalibration | None
             ) -> tuple[LearnedTerm | None, str | None]:
    """The diagnosis's learned residual term when it was kept, and a note when it was kept
    but cannot be used."""
    rm = diag.assessment.residual_model if diag.assessment is not None else None
    if rm is None or not rm.kept:
        return None, None
    if full is not None:
        return None, ("the learned residual term was kept by the diagnosis but is not in the "
                      "calibration: it was trained on the position-only model's residual, and "
                      "the calibration is the full-pose refit (use --no-orientation to "
                      "calibrate on positions with it)")
    return LearnedTerm.from_residual_model(rm), None
