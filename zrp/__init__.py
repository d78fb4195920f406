"""zrp: zero-reference-position kinematics and robot-accuracy analysis."""

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
from .kinematics import FKResult, end_effector_pose, forward_kinematics, jacobian
from .model import EndEffector, Joint, Manipulator, hand_frame
from .modelfile import builtin_models, dumps_model, load_model, loads_model, save_model

__version__ = "0.1.0"

__all__ = [
    "EndEffector",
    "FKResult",
    "IKError",
    "InputError",
    "Joint",
    "Manipulator",
    "ModelError",
    "ModelFileError",
    "OutputExistsError",
    "SingularityWarning",
    "TrackingWarning",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
    "builtin_models",
    "dumps_model",
    "end_effector_pose",
    "forward_kinematics",
    "hand_frame",
    "jacobian",
    "load_model",
    "loads_model",
    "save_model",
]
