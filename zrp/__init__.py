"""zrp: zero-reference-position kinematics and robot-accuracy analysis."""

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
from .trajectory import Circle, FunctionTrajectory, Line, TimeLaw, Trajectory, TrajectorySample

__version__ = "0.1.0"

__all__ = [
    "Circle",
    "DHRow",
    "EndEffector",
    "FKResult",
    "FunctionTrajectory",
    "IKError",
    "IKResult",
    "InputError",
    "Joint",
    "Line",
    "Manipulator",
    "ModelError",
    "ModelFileError",
    "OutputExistsError",
    "SingularityWarning",
    "TimeLaw",
    "TrackingWarning",
    "Trajectory",
    "TrajectorySample",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
    "builtin_models",
    "dumps_model",
    "end_effector_pose",
    "forward_kinematics",
    "from_dh",
    "from_mdh",
    "hand_frame",
    "jacobian",
    "load_model",
    "loads_model",
    "puma_circle",
    "puma_circle_ik",
    "save_model",
    "track_trajectory",
]
