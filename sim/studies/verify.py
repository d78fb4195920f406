"""A compensated joint program checked on the simulated robot it was calibrated on (``zrp verify``).

The robot and the tracker are rebuilt from the truth file ``zrp measure`` wrote beside its
measurements (the hidden effects, the tracker's placement and noise, the reflectors, and the
arm's own URDF/MJCF its dynamics came from, read again once its SHA-256 matches), so the
check runs on the same "real" robot and in the same tracker frame as the calibration. The
program is commanded as it is ("before"), then the compensated commands ("after"), each with
straight moves in program order (the approach directions the compensation assumed when none
were given). Both are measured by the tracker at every reflector.

The target of program row i at reflector j is where the program means it to be: the nominal
model's end point and hand frame at the program's joint values q_i, carrying the reflector as
the calibration identified it, seen by the tracker as the calibration registered it:

    y_ij = R_b (p_nom(q_i) + R_nom(q_i) F_nom F_cal^T t'_j) + t_b            (Eq V1)

(R_b, t_b: instrument-from-base registration; t'_j: reflector offset; F: hand frames of the
nominal and calibrated models; compensation reaches p_nom(q_i) with hand frame R_nom F_nom,
so its reflector sits there). The error per target is the RMS over its reflectors of
|measured - y_ij|; the tracker's pure noise is sqrt(3) sigma (sigma from the truth file). The
truth serves to rebuild the robot and nothing else.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mjcf.own_dynamics import arm_dynamics, file_sha256
from sim.robot.effects import HiddenEffects
from sim.robot.instrument import Instrument
from sim.robot.measurement import TRUTH_FORMAT, Procedure, measure
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from zrp.arrays import F64
from zrp.calibration import CalibratedRobot
from zrp.errors import InputError
from zrp.kinematics.forward import forward_kinematics
from zrp.model.manipulator import Manipulator

__all__ = ["ArmFileError", "Verification", "arm_options", "read_truth", "robot_from_truth",
           "verify_program"]

#: The largest truth file read (a truth file of 100,000 poses is about 30 MB).
MAX_TRUTH_BYTES = 256 * 2 ** 20


class ArmFileError(InputError):
    """The arm's own file a truth file names (its dynamics) is gone or no longer the same."""


@dataclass(frozen=True, eq=False)
class Verification:
    """Before/after errors of a compensated program on the simulated robot (T targets).

    Attributes:
        error_before, error_after: per target, RMS over the reflectors of the 3-D error
            (length unit), commanding the program as it is and the compensated commands.
        noise_rms: the tracker's pure-noise 3-D RMS, sqrt(3) sigma (length unit).
        points: the reflector labels measured.
    """

    error_before: F64
    error_after: F64
    noise_rms: float
    points: tuple[str, ...]

    @staticmethod
    def _rms(e: F64) -> float:
        return float(np.sqrt(np.mean(e ** 2)))

    def summary(self) -> dict[str, Any]:
        after = self._rms(self.error_after)
        return {"targets": len(self.error_after), "rms_before": self._rms(self.error_before),
                "rms_after": after, "max_after": float(self.error_after.max()),
                "noise_rms": self.noise_rms, "ratio_after_to_noise": after / self.noise_rms,
                "points": list(self.points)}


def read_truth(path: str | os.PathLike[str], field: str = "truth") -> dict[str, Any]:
    """The truth file ``zrp measure`` wrote (JSON), read as a dict.

    Raises:
        InputError: missing, not a regular file, larger than :data:`MAX_TRUTH_BYTES`, or not
            JSON (naming ``field``).
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{field}: {p} is not a file")
    if p.stat().st_size > MAX_TRUTH_BYTES:
        raise InputError(f"{field}: {p} is larger than {MAX_TRUTH_BYTES} bytes; not a truth file")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"{field}: {p} is not a JSON truth file ({exc})") from None
    if not isinstance(doc, dict):
        raise InputError(f"{field}: {p} is not a truth file of zrp measure")
    return doc


def robot_from_truth(model: Manipulator, truth: dict[str, Any], field: str = "truth"
                     ) -> tuple[RealRobot, Instrument]:
    """The simulated robot and tracker a truth file describes (as ``zrp measure`` built them).

    Raises:
        InputError: not a truth file, or one of another model (naming ``field``).
    """
    if not isinstance(truth, dict) or truth.get("format") != TRUTH_FORMAT:
        raise InputError(f"{field}: not a truth file of zrp measure (format "
                         f"{TRUTH_FORMAT!r})")
    if truth.get("model") != model.name or truth.get("length_unit") != model.length_unit:
        raise InputError(f"{field}: the truth is of model {truth.get('model')!r} in "
                         f"{truth.get('length_unit')!r}, not {model.name!r} in "
                         f"{model.length_unit!r}")
    try:
        effects = HiddenEffects.from_dict(truth["effects"])
        ins = truth["instrument"]
        inst = Instrument(float(ins["noise_sigma"]), tuple(ins["rotvec"]),
                          tuple(ins["translation"]))
        tool = np.asarray(truth["robot"]["tool_points"], dtype=float)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{field}: incomplete truth file ({exc})") from None
    robot = RealRobot(model, effects, arm_options(model, truth["robot"], field))
    if not np.allclose(np.asarray(robot.tool_points), tool, rtol=0, atol=1e-9):
        raise InputError(f"{field}: its reflectors differ from the simulated robot's "
                         "(written by another version)")
    return robot, inst


def arm_options(model: Manipulator, build: dict[str, Any], field: str = "truth"
                ) -> RealRobotOptions | None:
    """The options of the robot a truth file's ``robot`` block describes: the arm's own
    dynamics read again from the file it names, once its SHA-256 is checked (None: the
    robot had no file of its own).

    Raises:
        ArmFileError: the file is gone, or its bytes are not those the measurement read.
    """
    path = build.get("arm_file") if isinstance(build, dict) else None
    if not path:
        return None
    if not os.path.isfile(path):
        raise ArmFileError(f"{field}: the measured robot's dynamics came from {path}, which is "
                           "gone; restore it to rebuild the robot")
    digest = file_sha256(path)
    if digest != build.get("arm_sha256"):
        raise ArmFileError(f"{field}: {path} changed since the measurement (SHA-256 "
                           f"{digest[:16]}..., measured {str(build.get('arm_sha256'))[:16]}...);"
                           " restore the file the robot was measured with")
    return RealRobotOptions(dynamics=arm_dynamics(path, model))


def _targets(cal: CalibratedRobot, q: F64, labels: tuple[str, ...]) -> F64:
    """Eq V1 for every program row and reflector, shape (T, M, 3), instrument frame."""
    fk = forward_kinematics(cal.nominal, q)
    turn = cal.nominal.end_effector.frame @ cal.model.end_effector.frame.T
    offs = np.stack([cal.tool_offset(lab) for lab in labels])          # (M, 3)
    base = fk.position[:, None, :] + np.einsum("tij,jk,mk->tmi", fk.rotation, turn, offs)
    return cal.to_frame(base, "instrument")


def _measured(robot: RealRobot, inst: Instrument, q: F64, rng: np.random.Generator,
              labels: tuple[str, ...]) -> F64:
    """The reflectors measured at commands q, shape (T, M, 3), instrument frame."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meas = measure(robot, q, inst, rng, Procedure(approach="order")).measurements
    pts = np.asarray(meas.point)
    return np.stack([meas.xyz[pts == lab] for lab in labels], axis=1)


def verify_program(model: Manipulator, truth: dict[str, Any], cal: CalibratedRobot,
                   q_program: F64, q_command: F64, *, seed: int = 0) -> Verification:
    """Command ``q_program`` and ``q_command`` (T, n, rad) on the robot of ``truth`` and
    compare what the tracker measures with the program's targets (module doc, Eq V1).

    Raises:
        InputError: shapes, a truth of another model, reflectors unknown to the calibration.
    """
    qp, qc = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q_program, q_command))
    if qp.shape != qc.shape or qp.shape[1] != model.n:
        raise InputError(f"q_program, q_command: expected two arrays of shape (T, {model.n}),"
                         f" got {qp.shape} and {qc.shape}")
    robot, inst = robot_from_truth(model, truth)
    labels = tuple(f"smr{j + 1}" for j in range(len(robot.tool_points)))
    unknown = [lab for lab in labels if lab not in cal.tool_labels]
    if unknown:
        raise InputError(f"calibration: no tool point {', '.join(unknown)}; it knows "
                         f"{', '.join(cal.tool_labels)} (calibrated on another measurement?)")
    target = _targets(cal, qp, labels)
    rng = np.random.default_rng(seed)
    before = _measured(robot, inst, qp, rng, labels)
    after = _measured(robot, inst, qc, rng, labels)

    def err(m: F64) -> F64:
        return np.sqrt(np.mean(np.sum((m - target) ** 2, axis=2), axis=1))

    return Verification(err(before), err(after), float(np.sqrt(3.0) * inst.noise_sigma),
                        labels)
