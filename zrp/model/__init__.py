"""Manipulator models: the immutable :class:`Manipulator` (joints, axes u_{k,0}, body vectors
b_{k,0}, end effector), model files (TOML), DH/MDH tables and the built-in models.
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "DHRow": "zrp.model.dh",
    "dh_forward": "zrp.model.dh",
    "from_dh": "zrp.model.dh",
    "from_mdh": "zrp.model.dh",
    "mdh_forward": "zrp.model.dh",
    "builtin_models": "zrp.model.files",
    "dumps_model": "zrp.model.files",
    "load_model": "zrp.model.files",
    "loads_model": "zrp.model.files",
    "save_model": "zrp.model.files",
    "JOINT_TYPES": "zrp.model.manipulator",
    "EndEffector": "zrp.model.manipulator",
    "Joint": "zrp.model.manipulator",
    "Manipulator": "zrp.model.manipulator",
    "check_unit_vector": "zrp.model.manipulator",
    "check_vector3": "zrp.model.manipulator",
    "hand_frame": "zrp.model.manipulator",
    "URDFImport": "zrp.model.urdf",
    "URDFTree": "zrp.model.urdf",
    "from_urdf": "zrp.model.urdf",
    "import_urdf": "zrp.model.urdf",
    "read_urdf": "zrp.model.urdf",
    "save_urdf": "zrp.model.urdf_writer",
    "urdf_xml": "zrp.model.urdf_writer",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
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
    from zrp.model.urdf import URDFImport as URDFImport
    from zrp.model.urdf import URDFTree as URDFTree
    from zrp.model.urdf import from_urdf as from_urdf
    from zrp.model.urdf import import_urdf as import_urdf
    from zrp.model.urdf import read_urdf as read_urdf
    from zrp.model.urdf_writer import save_urdf as save_urdf
    from zrp.model.urdf_writer import urdf_xml as urdf_xml

__all__ = [
    "JOINT_TYPES",
    "DHRow",
    "EndEffector",
    "Joint",
    "Manipulator",
    "URDFImport",
    "URDFTree",
    "builtin_models",
    "check_unit_vector",
    "check_vector3",
    "dh_forward",
    "dumps_model",
    "from_dh",
    "from_mdh",
    "from_urdf",
    "hand_frame",
    "import_urdf",
    "load_model",
    "loads_model",
    "mdh_forward",
    "read_urdf",
    "save_model",
    "save_urdf",
    "urdf_xml",
]
