"""Kinematics by the zero-reference-position method: forward kinematics and the eq (7)
Jacobian (:mod:`.forward`, compiled in :mod:`._kernels`), trajectories (:mod:`.trajectory`),
predictor-corrector inverse kinematics along them (:mod:`.ik`, compiled in :mod:`._ik_kernels`),
random joint values (:mod:`.sampling`) and the kinematic parameter vector with its
identification Jacobian (:mod:`.identification`, used by calibration, the gap diagnosis and the
tolerance analysis). See README.md in this folder.
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "FKResult": "zrp.kinematics.forward",
    "check_q": "zrp.kinematics.forward",
    "end_effector_pose": "zrp.kinematics.forward",
    "forward_kinematics": "zrp.kinematics.forward",
    "jacobian": "zrp.kinematics.forward",
    "CORRECTIONS": "zrp.kinematics.ik",
    "TASKS": "zrp.kinematics.ik",
    "IKResult": "zrp.kinematics.ik",
    "track_trajectory": "zrp.kinematics.ik",
    "PoseSolution": "zrp.kinematics.posture",
    "Posture": "zrp.kinematics.posture",
    "check_limits_along": "zrp.kinematics.posture",
    "solve_pose": "zrp.kinematics.posture",
    "LIMIT_MODES": "zrp.kinematics.redundant",
    "track_posture": "zrp.kinematics.redundant",
    "reachable_poses": "zrp.kinematics.sampling",
    "uniform_joint_values": "zrp.kinematics.sampling",
    "TIME_LAWS": "zrp.kinematics.trajectory",
    "Circle": "zrp.kinematics.trajectory",
    "FunctionTrajectory": "zrp.kinematics.trajectory",
    "Line": "zrp.kinematics.trajectory",
    "OrientationLaw": "zrp.kinematics.trajectory",
    "TimeLaw": "zrp.kinematics.trajectory",
    "Trajectory": "zrp.kinematics.trajectory",
    "TrajectorySample": "zrp.kinematics.trajectory",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.kinematics.forward import FKResult as FKResult
    from zrp.kinematics.forward import check_q as check_q
    from zrp.kinematics.forward import end_effector_pose as end_effector_pose
    from zrp.kinematics.forward import forward_kinematics as forward_kinematics
    from zrp.kinematics.forward import jacobian as jacobian
    from zrp.kinematics.ik import CORRECTIONS as CORRECTIONS
    from zrp.kinematics.ik import TASKS as TASKS
    from zrp.kinematics.ik import IKResult as IKResult
    from zrp.kinematics.ik import track_trajectory as track_trajectory
    from zrp.kinematics.posture import PoseSolution as PoseSolution
    from zrp.kinematics.posture import Posture as Posture
    from zrp.kinematics.posture import check_limits_along as check_limits_along
    from zrp.kinematics.posture import solve_pose as solve_pose
    from zrp.kinematics.redundant import LIMIT_MODES as LIMIT_MODES
    from zrp.kinematics.redundant import track_posture as track_posture
    from zrp.kinematics.sampling import reachable_poses as reachable_poses
    from zrp.kinematics.sampling import uniform_joint_values as uniform_joint_values
    from zrp.kinematics.trajectory import TIME_LAWS as TIME_LAWS
    from zrp.kinematics.trajectory import Circle as Circle
    from zrp.kinematics.trajectory import FunctionTrajectory as FunctionTrajectory
    from zrp.kinematics.trajectory import Line as Line
    from zrp.kinematics.trajectory import OrientationLaw as OrientationLaw
    from zrp.kinematics.trajectory import TimeLaw as TimeLaw
    from zrp.kinematics.trajectory import Trajectory as Trajectory
    from zrp.kinematics.trajectory import TrajectorySample as TrajectorySample

__all__ = [
    "CORRECTIONS",
    "LIMIT_MODES",
    "TASKS",
    "TIME_LAWS",
    "Circle",
    "FKResult",
    "FunctionTrajectory",
    "IKResult",
    "Line",
    "OrientationLaw",
    "PoseSolution",
    "Posture",
    "TimeLaw",
    "Trajectory",
    "TrajectorySample",
    "check_limits_along",
    "check_q",
    "end_effector_pose",
    "forward_kinematics",
    "jacobian",
    "reachable_poses",
    "solve_pose",
    "track_posture",
    "track_trajectory",
    "uniform_joint_values",
]
