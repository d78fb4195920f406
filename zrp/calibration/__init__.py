"""Closing the calibration loop (README.md in this folder): the calibrated robot taken out of
a gap diagnosis (model TOML + compensation JSON) and compensation of targets.

In-process use (the one recipe, :func:`calibrate`, that ``zrp calibrate``, the notebooks and
the studies call)::

    from zrp.calibration import CalibrationOptions, calibrate, compensate
    result = calibrate(model, meas, options=CalibrationOptions(gravity_torque=tau))
    result.write("calibrated.toml", "compensation.json")
    comp = compensate(result.robot, targets_xyz, seed_q, point="s1", frame="instrument",
                      limits=lim)
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "CalibratedRobot": "zrp.calibration.calibrated",
    "Calibration": "zrp.calibration.recipe",
    "CalibrationOptions": "zrp.calibration.recipe",
    "calibrate": "zrp.calibration.recipe",
    "PoseConditions": "zrp.calibration.calibrated",
    "Compensation": "zrp.calibration.compensation",
    "ThermalWarning": "zrp.calibration.compensation",
    "compensate": "zrp.calibration.compensation",
    "compensate_program": "zrp.calibration.compensation",
    "PoseAccuracy": "zrp.calibration.iso9283",
    "pose_accuracy": "zrp.calibration.iso9283",
    "Term": "zrp.calibration.jointmap",
    "Plan": "zrp.calibration.planning",
    "PlanWarning": "zrp.calibration.planning",
    "design_std": "zrp.calibration.planning",
    "plan_poses": "zrp.calibration.planning",
    "read_calibration": "zrp.calibration.storage",
    "write_calibration": "zrp.calibration.storage",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
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
    from zrp.calibration.recipe import Calibration as Calibration
    from zrp.calibration.recipe import CalibrationOptions as CalibrationOptions
    from zrp.calibration.recipe import calibrate as calibrate
    from zrp.calibration.storage import read_calibration as read_calibration
    from zrp.calibration.storage import write_calibration as write_calibration

__all__ = [
    "CalibratedRobot",
    "Calibration",
    "CalibrationOptions",
    "Compensation",
    "Plan",
    "PlanWarning",
    "PoseAccuracy",
    "PoseConditions",
    "Term",
    "ThermalWarning",
    "calibrate",
    "compensate",
    "compensate_program",
    "design_std",
    "plan_poses",
    "pose_accuracy",
    "read_calibration",
    "write_calibration",
]
