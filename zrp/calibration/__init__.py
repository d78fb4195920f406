"""Closing the calibration loop (README.md in this folder): the calibrated robot taken out of
a gap diagnosis (model TOML + compensation JSON) and compensation of targets.

In-process use::

    from zrp.calibration import CalibratedRobot, write_calibration, compensate
    cal = CalibratedRobot.from_diagnosis(diag)
    write_calibration(cal, "calibrated.toml", "compensation.json")
    comp = compensate(cal, targets_xyz, seed_q, point="s1", frame="instrument", limits=lim)
"""

from zrp.calibration.calibrated import CalibratedRobot as CalibratedRobot
from zrp.calibration.calibrated import PoseConditions as PoseConditions
from zrp.calibration.compensation import Compensation as Compensation
from zrp.calibration.compensation import ThermalWarning as ThermalWarning
from zrp.calibration.compensation import compensate as compensate
from zrp.calibration.compensation import compensate_program as compensate_program
from zrp.calibration.iso9283 import PoseAccuracy as PoseAccuracy
from zrp.calibration.iso9283 import pose_accuracy as pose_accuracy
from zrp.calibration.jointmap import Term as Term
from zrp.calibration.planning import Plan as Plan
from zrp.calibration.planning import PlanWarning as PlanWarning
from zrp.calibration.planning import design_std as design_std
from zrp.calibration.planning import plan_poses as plan_poses
from zrp.calibration.storage import read_calibration as read_calibration
from zrp.calibration.storage import write_calibration as write_calibration

__all__ = [
    "CalibratedRobot",
    "Compensation",
    "Plan",
    "PlanWarning",
    "PoseAccuracy",
    "PoseConditions",
    "Term",
    "ThermalWarning",
    "compensate",
    "compensate_program",
    "design_std",
    "plan_poses",
    "pose_accuracy",
    "read_calibration",
    "write_calibration",
]
