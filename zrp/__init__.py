"""zrp: zero-reference-position kinematics and robot-accuracy analysis."""

import importlib
from typing import Any

from .deviation import Deviation, pose_deviation, trajectory_deviation
from .dh import DHRow, from_dh, from_mdh
from .errors import (
    IKError,
    InputError,
    ModelError,
    ModelFileError,
    OutputExistsError,
    SingularityWarning,
    TrackingWarning,
    UnreachableError,
    ZRPError,
    ZRPWarning,
)
from .examples import puma_circle, puma_circle_ik
from .ik import IKResult, track_trajectory
from .kinematics import FKResult, end_effector_pose, forward_kinematics, jacobian
from .model import EndEffector, Joint, Manipulator, hand_frame
from .modelfile import builtin_models, dumps_model, load_model, loads_model, save_model
from .paper import run_paper_example, write_paper_outputs
from .perturb import PAPER_SIGN_ZERO, Perturbation
from .sensitivity import (
    apply_parameters,
    parameter_jacobian,
    parameter_names,
    parameter_space,
    pose_error,
)
from .study import JointPath, StudyResult, circle_joint_path, load_joint_csv, one_at_a_time
from .tolerance import Allocation, MonteCarloResult, Tolerances, allocate_tolerances, monte_carlo
from .trajectory import Circle, FunctionTrajectory, Line, TimeLaw, Trajectory, TrajectorySample

__version__ = "0.1.0"

# The gap diagnosis pulls in scipy.stats (about 1 s): load it on first use, not with `import zrp`.
_LAZY = {name: "gap" for name in
         ("Diagnosis", "Measurements", "diagnose", "load_measurements", "write_outputs")}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'zrp' has no attribute {name!r}")


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
    "JointPath",
    "Line",
    "Manipulator",
    "Measurements",
    "ModelError",
    "ModelFileError",
    "MonteCarloResult",
    "OutputExistsError",
    "Perturbation",
    "SingularityWarning",
    "StudyResult",
    "TimeLaw",
    "Tolerances",
    "TrackingWarning",
    "Trajectory",
    "TrajectorySample",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
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
    "hand_frame",
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
    "run_paper_example",
    "save_model",
    "track_trajectory",
    "trajectory_deviation",
    "write_outputs",
    "write_paper_outputs",
]
