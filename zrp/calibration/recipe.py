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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.conditions import Conditions
from zrp.calibration.fullpose import FullPoseCalibration, full_pose_calibration
from zrp.calibration.learned import LearnedTerm
from zrp.calibration.storage import write_calibration
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements
from zrp.gap.finalrecord import FinalModelRecord, StaleDiagnosisError
from zrp.gap.model.choices import EFFECTS
from zrp.gap.model.domains import DEFAULT_MAX_TILT_RAD
from zrp.gap.pipeline import diagnose
from zrp.gap.results import SCHEMA_VERSION, Diagnosis
from zrp.jsonio import MAX_DIAGNOSIS_BYTES, read_json
from zrp.model.manipulator import Manipulator

__all__ = ["Calibration", "CalibrationOptions", "calibrate", "stored_record"]


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
            (``zrp diagnose --residual-model``); when the diagnosis keeps it (what remains has
            structure and it lowers the withheld error clearly) the calibrated robot carries
            it (``learned``, :mod:`zrp.calibration.learned`), unless the calibration is a
            full-pose refit (the term was trained on the position-only final model's
            residual).
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
        diagnosis: the diagnosis the calibration came from, or None when it came from a stored
            one (diagnosis.json: its ``final_model_record`` only).
        robot: the calibrated robot (the full-pose refit's when the diagnosis has one), with
            the data's conditions and the widened domains.
        full_pose: the full-pose calibration (measured orientations; its summary), or None
            (none, or a stored diagnosis).
        record: what the robot was built from (:class:`zrp.gap.FinalModelRecord`).
        learned_note: why a kept learned residual term is not in the calibrated robot, or
            None.
    """

    diagnosis: Diagnosis | None
    robot: CalibratedRobot
    full_pose: FullPoseCalibration | None = None
    record: FinalModelRecord | None = None
    learned_note: str | None = None

    def write(self, model_path: str | Path, comp_path: str | Path, *,
              overwrite: bool = False) -> list[Path]:
        """Write calibrated.toml and compensation.json
        (:func:`~zrp.calibration.write_calibration`)."""
        probe = (self.record.probe if self.record is not None
                 else None if self.full_pose is None else self.full_pose.fit)
        return list(write_calibration(self.robot, model_path, comp_path, overwrite=overwrite,
                                      full_pose=probe))


#: the options that shape a diagnosis: a stored or given diagnosis has its own
_DIAGNOSIS_FIELDS = ("gravity_torque", "effects", "seed", "max_steps", "noise_sigma",
                     "use_orientation", "orientation_sigma", "residual_model")


def _differs(value: Any, default: Any) -> bool:
    if default is None or value is None:
        return value is not default
    return tuple(np.atleast_1d(value)) != tuple(np.atleast_1d(default))


def _refuse_diagnosis_options(opt: CalibrationOptions) -> None:
    default = CalibrationOptions()
    given = [f for f in _DIAGNOSIS_FIELDS if _differs(getattr(opt, f), getattr(default, f))]
    if given:
        raise InputError(f"options: {', '.join(given)} shape a diagnosis, and the one given "
                         "has its own (its settings); leave them at their defaults, or "
                         "calibrate without a diagnosis to diagnose anew")


def stored_record(source: str | Path | Mapping[str, Any]) -> FinalModelRecord:
    """The final-model record of a stored diagnosis: a diagnosis.json path or its document.

    Raises:
        StaleDiagnosisError: a diagnosis.json without a ``final_model_record`` (schema_version
            1, written before 0.5.0), naming the file and saying to re-run ``zrp diagnose``.
        InputError: unreadable or malformed.
    """
    doc, src = _stored_document(source)
    return FinalModelRecord.from_dict(doc["final_model_record"], f"{src}: final_model_record")


def _stored_document(source: str | Path | Mapping[str, Any]) -> tuple[Mapping[str, Any], str]:
    src = "diagnosis" if isinstance(source, Mapping) else str(source)
    doc = source if isinstance(source, Mapping) else read_json(
        source, label=src, max_bytes=MAX_DIAGNOSIS_BYTES, what="diagnosis.json")
    if not isinstance(doc, Mapping):
        raise InputError(f"{src}: expected a diagnosis.json object")
    version = doc.get("schema_version")
    if "final_model_record" not in doc:
        raise StaleDiagnosisError(
            f"{src}: schema_version {version!r} (zrp-accuracy {doc.get('zrp_version', '?')}) "
            "holds no final_model_record, which a calibration needs; re-run zrp diagnose "
            f"with this version (schema_version {SCHEMA_VERSION}) to reuse a diagnosis, or "
            "calibrate without --diagnosis")
    if version != SCHEMA_VERSION:
        raise StaleDiagnosisError(f"{src}: schema_version {version!r}, expected "
                                  f"{SCHEMA_VERSION}; re-run zrp diagnose with this version")
    return doc, src


def calibrate(model: Manipulator, measurements: Measurements, *,
              options: CalibrationOptions | None = None,
              diagnosis: Diagnosis | str | Path | Mapping[str, Any] | None = None
              ) -> Calibration:
    """Calibrate ``model`` from ``measurements``: diagnose (or take ``diagnosis``: a
    diagnosis of these measurements, or a stored one, a diagnosis.json path or document),
    take the calibrated robot of its final model out (its full-pose refit when the diagnosis
    has one; :class:`zrp.gap.FinalModelRecord`, which a stored diagnosis holds, so no search
    is repeated), and record the data's conditions and the widened domains. Every number
    passes the record's JSON form, so a stored diagnosis gives the same files as a fresh run.

    Raises:
        InputError: ``options`` is not a :class:`CalibrationOptions`; diagnosis-shaping
            options given with a ``diagnosis``.
        StaleDiagnosisError: ``diagnosis`` is of other measurements or another model, or a
            diagnosis.json written before it held its final model's record.
    """
    opt = CalibrationOptions() if options is None else options
    if not isinstance(opt, CalibrationOptions):
        raise InputError(f"options: expected CalibrationOptions, got {type(opt).__name__}")
    if diagnosis is not None:
        _refuse_diagnosis_options(opt)
    src, stored_kept = _source(diagnosis)
    diagnosis, record, full, meas_check = _final_record(model, measurements, opt, diagnosis)
    record.check(model, measurements if meas_check else None, src)
    cond = Conditions.from_measurements(
        measurements, model, data_path=opt.data_path, data_angle_unit=opt.data_angle_unit,
        instrument=opt.instrument)
    widen = None if opt.widen is None else dict(opt.widen)
    robot = CalibratedRobot.from_record(record, model, cond, widen)
    learned, note = _learned(diagnosis, full, stored=stored_kept)
    if learned is not None:
        robot = dataclasses.replace(robot, learned=learned)
    return Calibration(diagnosis, robot, full, record, note)


def _source(diagnosis: Diagnosis | str | Path | Mapping[str, Any] | None) -> tuple[str, bool]:
    """How errors name the diagnosis, and whether it is a stored one that kept a learned
    residual term (diagnosis.json says so, without the term itself)."""
    if diagnosis is None or isinstance(diagnosis, Diagnosis):
        return "diagnosis", False
    if isinstance(diagnosis, Mapping):
        doc, src = diagnosis, "diagnosis"
    else:
        doc, src = _stored_document(diagnosis)
    rm = doc.get("residual_model")
    return src, isinstance(rm, Mapping) and rm.get("kept") is True


def _final_record(model: Manipulator, measurements: Measurements, opt: CalibrationOptions,
                  diagnosis: Diagnosis | str | Path | Mapping[str, Any] | None
                  ) -> tuple[Diagnosis | None, FinalModelRecord,
                             FullPoseCalibration | None, bool]:
    """The diagnosis (None for a stored one), its final model's record in the JSON form
    diagnosis.json stores, its full-pose calibration, and whether the record's measurements
    must be checked against ``measurements``."""
    if diagnosis is not None and not isinstance(diagnosis, Diagnosis):
        return None, stored_record(diagnosis), None, True
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
        raise StaleDiagnosisError(f"diagnosis: it diagnosed {diagnosis.context.meas.source}, "
                                  f"not {measurements.source}")
    # the record in its JSON form, exactly as diagnosis.json stores it
    record = FinalModelRecord.from_dict(diagnosis.calibration_record.to_dict(), "diagnosis")
    full = None if diagnosis.full_pose is None else full_pose_calibration(
        diagnosis, diagnosis.settings.get("orientation_sigma_rad"))
    return diagnosis, record, full, diagnosis.context.meas is not measurements


def _learned(diag: Diagnosis | None, full: FullPoseCalibration | None, *, stored: bool = False
             ) -> tuple[LearnedTerm | None, str | None]:
    """The diagnosis's learned residual term when it was kept, and a note when it was kept
    but cannot be used."""
    if stored:
        return None, ("the stored diagnosis kept a learned residual term, but diagnosis.json "
                      "does not hold it: the calibration is the physical model alone "
                      "(calibrate with --residual-model, without --diagnosis, to include it)")
    rm = None if diag is None or diag.assessment is None else diag.assessment.residual_model
    if rm is None or not rm.kept:
        return None, None
    if full is not None:
        return None, ("the learned residual term was kept by the diagnosis but is not in the "
                      "calibration: it was trained on the position-only model's residual, and "
                      "the calibration is the full-pose refit (use --no-orientation to "
                      "calibrate on positions with it)")
    return LearnedTerm.from_residual_model(rm), None
