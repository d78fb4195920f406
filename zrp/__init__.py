"""zrp: zero-reference-position kinematics and robot-accuracy analysis."""

from typing import TYPE_CHECKING

from zrp.errors import (
    IKError,
    InputError,
    JointLimitError,
    ModelError,
    ModelFileError,
    OutputExistsError,
    SingularityError,
    SingularityWarning,
    TrackingWarning,
    UnitError,
    UnreachableError,
    ZRPError,
    ZRPWarning,
)
from zrp.lazy import lazy_names
from zrp.version import __version__

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "Diagnosis": "zrp.gap",
    "Measurements": "zrp.gap",
    "diagnose": "zrp.gap",
    "load_measurements": "zrp.gap",
    "write_outputs": "zrp.gap",
    "FKResult": "zrp.kinematics.forward",
    "end_effector_pose": "zrp.kinematics.forward",
    "forward_kinematics": "zrp.kinematics.forward",
    "jacobian": "zrp.kinematics.forward",
    "apply_parameters": "zrp.kinematics.identification",
    "parameter_jacobian": "zrp.kinematics.identification",
    "parameter_names": "zrp.kinematics.identification",
    "parameter_space": "zrp.kinematics.identification",
    "pose_error": "zrp.kinematics.identification",
    "IKResult": "zrp.kinematics.ik",
    "track_trajectory": "zrp.kinematics.ik",
    "PoseSolution": "zrp.kinematics.posture",
    "solve_pose": "zrp.kinematics.posture",
    "track_posture": "zrp.kinematics.redundant",
    "reachable_poses": "zrp.kinematics.sampling",
    "uniform_joint_values": "zrp.kinematics.sampling",
    "Circle": "zrp.kinematics.trajectory",
    "FunctionTrajectory": "zrp.kinematics.trajectory",
    "Line": "zrp.kinematics.trajectory",
    "TimeLaw": "zrp.kinematics.trajectory",
    "Trajectory": "zrp.kinematics.trajectory",
    "TrajectorySample": "zrp.kinematics.trajectory",
    "Allocation": "zrp.manufacturing.allocation",
    "allocate_tolerances": "zrp.manufacturing.allocation",
    "Deviation": "zrp.manufacturing.deviation",
    "pose_deviation": "zrp.manufacturing.deviation",
    "trajectory_deviation": "zrp.manufacturing.deviation",
    "PAPER_SIGN_ZERO": "zrp.manufacturing.perturb",
    "Perturbation": "zrp.manufacturing.perturb",
    "MonteCarloResult": "zrp.manufacturing.population",
    "monte_carlo": "zrp.manufacturing.population",
    "JointPath": "zrp.manufacturing.study",
    "StudyResult": "zrp.manufacturing.study",
    "load_joint_csv": "zrp.manufacturing.study",
    "one_at_a_time": "zrp.manufacturing.study",
    "Tolerances": "zrp.manufacturing.tolerance",
    "DHRow": "zrp.model.dh",
    "from_dh": "zrp.model.dh",
    "from_mdh": "zrp.model.dh",
    "builtin_models": "zrp.model.files",
    "dumps_model": "zrp.model.files",
    "load_model": "zrp.model.files",
    "loads_model": "zrp.model.files",
    "save_model": "zrp.model.files",
    "EndEffector": "zrp.model.manipulator",
    "Joint": "zrp.model.manipulator",
    "Manipulator": "zrp.model.manipulator",
    "hand_frame": "zrp.model.manipulator",
    "URDFImport": "zrp.model.urdf",
    "from_urdf": "zrp.model.urdf",
    "import_urdf": "zrp.model.urdf",
    "save_urdf": "zrp.model.urdf_writer",
    "urdf_xml": "zrp.model.urdf_writer",
    "run_paper_example": "zrp.paper.example",
    "write_paper_outputs": "zrp.paper.report",
    "circle_joint_path": "zrp.paper.scenario",
    "puma_circle": "zrp.paper.scenario",
    "puma_circle_ik": "zrp.paper.scenario",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.gap import Diagnosis as Diagnosis
    from zrp.gap import Measurements as Measurements
    from zrp.gap import diagnose as diagnose
    from zrp.gap import load_measurements as load_measurements
    from zrp.gap import write_outputs as write_outputs
    from zrp.kinematics.forward import FKResult as FKResult
    from zrp.kinematics.forward import end_effector_pose as end_effector_pose
    from zrp.kinematics.forward import forward_kinematics as forward_kinematics
    from zrp.kinematics.forward import jacobian as jacobian
    from zrp.kinematics.identification import apply_parameters as apply_parameters
    from zrp.kinematics.identification import parameter_jacobian as parameter_jacobian
    from zrp.kinematics.identification import parameter_names as parameter_names
    from zrp.kinematics.identification import parameter_space as parameter_space
    from zrp.kinematics.identification import pose_error as pose_error
    from zrp.kinematics.ik import IKResult as IKResult
    from zrp.kinematics.ik import track_trajectory as track_trajectory
    from zrp.kinematics.posture import PoseSolution as PoseSolution
    from zrp.kinematics.posture import solve_pose as solve_pose
    from zrp.kinematics.redundant import track_posture as track_posture
    from zrp.kinematics.sampling import reachable_poses as reachable_poses
    from zrp.kinematics.sampling import uniform_joint_values as uniform_joint_values
    from zrp.kinematics.trajectory import Circle as Circle
    from zrp.kinematics.trajectory import FunctionTrajectory as FunctionTrajectory
    from zrp.kinematics.trajectory import Line as Line
    from zrp.kinematics.trajectory import TimeLaw as TimeLaw
    from zrp.kinematics.trajectory import Trajectory as Trajectory
    from zrp.kinematics.trajectory import TrajectorySample as TrajectorySample
    from zrp.manufacturing.allocation import Allocation as Allocation
    from zrp.manufacturing.allocation import allocate_tolerances as allocate_tolerances
    from zrp.manufacturing.deviation import Deviation as Deviation
    from zrp.manufacturing.deviation import pose_deviation as pose_deviation
    from zrp.manufacturing.deviation import trajectory_deviation as trajectory_deviation
    from zrp.manufacturing.perturb import PAPER_SIGN_ZERO as PAPER_SIGN_ZERO
    from zrp.manufacturing.perturb import Perturbation as Perturbation
    from zrp.manufacturing.population import MonteCarloResult as MonteCarloResult
    from zrp.manufacturing.population import monte_carlo as monte_carlo
    from zrp.manufacturing.study import JointPath as JointPath
    from zrp.manufacturing.study import StudyResult as StudyResult
    from zrp.manufacturing.study import load_joint_csv as load_joint_csv
    from zrp.manufacturing.study import one_at_a_time as one_at_a_time
    from zrp.manufacturing.tolerance import Tolerances as Tolerances
    from zrp.model.dh import DHRow as DHRow
    from zrp.model.dh import from_dh as from_dh
    from zrp.model.dh import from_mdh as from_mdh
    from zrp.model.files import builtin_models as builtin_models
    from zrp.model.files import dumps_model as dumps_model
    from zrp.model.files import load_model as load_model
    from zrp.model.files import loads_model as loads_model
    from zrp.model.files import save_model as save_model
    from zrp.model.manipulator import EndEffector as EndEffector
    from zrp.model.manipulator import Joint as Joint
    from zrp.model.manipulator import Manipulator as Manipulator
    from zrp.model.manipulator import hand_frame as hand_frame
    from zrp.model.urdf import URDFImport as URDFImport
    from zrp.model.urdf import from_urdf as from_urdf
    from zrp.model.urdf import import_urdf as import_urdf
    from zrp.model.urdf_writer import save_urdf as save_urdf
    from zrp.model.urdf_writer import urdf_xml as urdf_xml
    from zrp.paper.example import run_paper_example as run_paper_example
    from zrp.paper.report import write_paper_outputs as write_paper_outputs
    from zrp.paper.scenario import circle_joint_path as circle_joint_path
    from zrp.paper.scenario import puma_circle as puma_circle
    from zrp.paper.scenario import puma_circle_ik as puma_circle_ik

__all__ = [
    "PAPER_SIGN_ZERO",
    "Allocation",
    "Circle",
    "DHRow",
    "Deviation",
    "Diagnosis",
    "EndEffector",
    "FKResult",
    "FunctionTrajectory",
    "IKError",
    "IKResult",
    "InputError",
    "Joint",
    "JointLimitError",
    "JointPath",
    "Line",
    "Manipulator",
    "Measurements",
    "ModelError",
    "ModelFileError",
    "MonteCarloResult",
    "OutputExistsError",
    "Perturbation",
    "PoseSolution",
    "SingularityError",
    "SingularityWarning",
    "StudyResult",
    "TimeLaw",
    "Tolerances",
    "TrackingWarning",
    "Trajectory",
    "TrajectorySample",
    "URDFImport",
    "UnitError",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
    "__version__",
    "allocate_tolerances",
    "apply_parameters",
    "builtin_models",
    "circle_joint_path",
    "diagnose",
    "dumps_model",
    "end_effector_pose",
    "forward_kinematics",
    "from_dh",
    "from_mdh",
    "from_urdf",
    "hand_frame",
    "import_urdf",
    "jacobian",
    "load_joint_csv",
    "load_measurements",
    "load_model",
    "loads_model",
    "monte_carlo",
    "one_at_a_time",
    "parameter_jacobian",
    "parameter_names",
    "parameter_space",
    "pose_deviation",
    "pose_error",
    "puma_circle",
    "puma_circle_ik",
    "reachable_poses",
    "run_paper_example",
    "save_model",
    "save_urdf",
    "solve_pose",
    "track_posture",
    "track_trajectory",
    "trajectory_deviation",
    "uniform_joint_values",
    "urdf_xml",
    "write_outputs",
    "write_paper_outputs",
]
