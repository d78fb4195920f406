"""zrp: zero-reference-position kinematics and robot-accuracy analysis."""

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
from zrp.gap import Diagnosis, Measurements, diagnose, load_measurements, write_outputs
from zrp.kinematics.forward import FKResult, end_effector_pose, forward_kinematics, jacobian
from zrp.kinematics.identification import (
    apply_parameters,
    parameter_jacobian,
    parameter_names,
    parameter_space,
    pose_error,
)
from zrp.kinematics.ik import IKResult, track_trajectory
from zrp.kinematics.posture import PoseSolution, solve_pose
from zrp.kinematics.redundant import track_posture
from zrp.kinematics.sampling import reachable_poses, uniform_joint_values
from zrp.kinematics.trajectory import (
    Circle,
    FunctionTrajectory,
    Line,
    TimeLaw,
    Trajectory,
    TrajectorySample,
)
from zrp.manufacturing.allocation import Allocation, allocate_tolerances
from zrp.manufacturing.deviation import Deviation, pose_deviation, trajectory_deviation
from zrp.manufacturing.perturb import PAPER_SIGN_ZERO, Perturbation
from zrp.manufacturing.population import MonteCarloResult, monte_carlo
from zrp.manufacturing.study import JointPath, StudyResult, load_joint_csv, one_at_a_time
from zrp.manufacturing.tolerance import Tolerances
from zrp.model.dh import DHRow, from_dh, from_mdh
from zrp.model.files import builtin_models, dumps_model, load_model, loads_model, save_model
from zrp.model.manipulator import EndEffector, Joint, Manipulator, hand_frame
from zrp.model.urdf import URDFImport, from_urdf, import_urdf
from zrp.model.urdf_writer import save_urdf, urdf_xml
from zrp.paper.example import run_paper_example
from zrp.paper.report import write_paper_outputs
from zrp.paper.scenario import circle_joint_path, puma_circle, puma_circle_ik
from zrp.version import __version__

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
