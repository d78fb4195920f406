"""Manipulator models: the immutable :class:`Manipulator` (joints, axes u_{k,0}, body vectors
b_{k,0}, end effector), model files (TOML), DH/MDH tables and the built-in models.
"""

from zrp.model.dh import DHRow as DHRow
from zrp.model.dh import dh_forward as dh_forward
from zrp.model.dh import from_dh as from_dh
from zrp.model.dh import from_mdh as from_mdh
from zrp.model.dh import mdh_forward as mdh_forward
from zrp.model.files import builtin_models as builtin_models
from zrp.model.files import dumps_model as dumps_model
from zrp.model.files import load_model as load_model
from zrp.model.files import loads_model as loads_model
from zrp.model.files import save_model as save_model
from zrp.model.manipulator import JOINT_TYPES as JOINT_TYPES
from zrp.model.manipulator import EndEffector as EndEffector
from zrp.model.manipulator import Joint as Joint
from zrp.model.manipulator import Manipulator as Manipulator
from zrp.model.manipulator import check_unit_vector as check_unit_vector
from zrp.model.manipulator import check_vector3 as check_vector3
from zrp.model.manipulator import hand_frame as hand_frame

__all__ = [
    "JOINT_TYPES",
    "DHRow",
    "EndEffector",
    "Joint",
    "Manipulator",
    "builtin_models",
    "check_unit_vector",
    "check_vector3",
    "dh_forward",
    "dumps_model",
    "from_dh",
    "from_mdh",
    "hand_frame",
    "load_model",
    "loads_model",
    "mdh_forward",
    "save_model",
]
