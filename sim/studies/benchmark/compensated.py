"""Blind benchmark, the "compensated" column: what compensation achieves on the real robot.

After a scenario has been diagnosed blind and scored, the calibrated robot is taken out of
its diagnosis (:class:`zrp.calibration.CalibratedRobot`) and fresh targets are compensated,
commanded on the same real robot, measured by the same tracker and compared
(:func:`sim.studies.compensation_check.compensate_and_measure`): targets are where the
registration-only model puts reflector ``smr1`` for a fresh program (random reachable poses,
plus points of the paper's circle for a 6-joint arm), each approached from a chosen side; the
compensation is computed for the temperatures logged while the program ran as it is. Only
the measured errors are used; the truth file gives nothing but the tracker's placement (the
same tracker measures again) and the hidden effects of the robot being commanded.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from sim.robot.instrument import Instrument
from sim.robot.mass import DynamicsFallbackWarning
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from sim.studies.benchmark.scenarios import Scenario
from sim.studies.compensation_check import compensate_and_measure
from zrp.calibration import calibrate
from zrp.errors import InputError
from zrp.gap import Diagnosis
from zrp.model.manipulator import Manipulator

__all__ = ["COMPENSATED_KEYS", "compensated_column"]

#: the keys :func:`compensated_column` adds to a scenario's score (its ``values``).
COMPENSATED_KEYS = ("comp_targets", "comp_rms_before", "comp_rms_after", "comp_ratio",
                    "comp_ratio_before", "comp_predicted_max", "comp_error")


def compensated_column(model: Manipulator, scenario: Scenario, truth: dict[str, Any],
                       diagnosis: Diagnosis, mjcf_path: Path | None, targets: int,
                       options: RealRobotOptions | None = None) -> dict[str, Any]:
    """Compensate ``targets`` fresh random targets (and ``targets // 2`` circle points for a
    6-joint arm) with the scenario's diagnosis, command and measure them (module doc).

    Returns:
        the :data:`COMPENSATED_KEYS`: number of targets, measured RMS (3-D) before and after
        compensation (length unit), after and before over the pure-noise RMS sqrt(3) sigma,
        the largest predicted residual, and the error text when compensation refused
        (then the numbers are NaN).
    """
    ins = truth["instrument"]
    inst = Instrument(float(ins["noise_sigma"]), tuple(ins["rotvec"]),
                      tuple(ins["translation"]))
    tool = tuple(tuple(float(x) for x in r) for r in truth["robot"]["tool_points"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsFallbackWarning)  # the run's report says it
        robot = RealRobot(model, scenario.effects, dataclasses.replace(
            options or RealRobotOptions(), tool_points=tool))
    rng = np.random.default_rng([scenario.seed, 11])
    n_circle = targets // 2 if model.n == 6 and targets // 2 >= 8 else 0
    nan = float("nan")
    calibration = calibrate(model, diagnosis.context.meas, diagnosis=diagnosis)
    try:
        try:
            r = compensate_and_measure(robot, inst, calibration, mjcf_path, rng,
                                       n_random=targets, n_circle=n_circle, chosen_side=True)
        except InputError as exc:
            if n_circle == 0 or "circle" not in str(exc):
                raise
            r = compensate_and_measure(robot, inst, calibration, mjcf_path, rng,
                                       n_random=targets, n_circle=0, chosen_side=True)
    except InputError as exc:  # e.g. a command beyond a limit: reported, not a crash
        return {"comp_targets": 0, "comp_rms_before": nan, "comp_rms_after": nan,
                "comp_ratio": nan, "comp_ratio_before": nan, "comp_predicted_max": nan,
                "comp_error": str(exc)}
    return {"comp_targets": len(r.labels), "comp_rms_before": r.rms_before,
            "comp_rms_after": r.rms_after, "comp_ratio": r.rms_after / r.noise_rms,
            "comp_ratio_before": r.rms_before / r.noise_rms,
            "comp_predicted_max": float(r.compensation.residual.max()), "comp_error": ""}
