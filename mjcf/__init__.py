"""MJCF models of ZRP manipulators (built with mujoco.MjSpec) and import from MJCF/URDF.

* :func:`build` compiles a :class:`zrp.Manipulator` (nominal or perturbed) into a MuJoCo model
  whose qpos = 0 is the zero reference position; :func:`save_mjcf` writes it as XML.
* :func:`manipulator_from_mujoco` / :func:`from_mjcf` read a serial arm from MJCF or URDF.
"""

from mjcf import _env  # noqa: F401 (checks MUJOCO_GL before any module imports mujoco)
from mjcf.builder import BuiltArm, MJCFOptions, build, build_spec
from mjcf.dynamics import inverse_dynamics_torques, mode_terms
from mjcf.errors import MJCFCompileError, MJCFImportError, MJCFOutputError
from mjcf.gravity import gravity_torques
from mjcf.importer import from_mjcf, load_mujoco_model, manipulator_from_mujoco
from mjcf.inertia import INERTIA_MODELS, BodyInertia, puma560_inertias, rod_inertias
from mjcf.own_dynamics import ArmDynamics, arm_dynamics
from mjcf.shipped import load_shipped, load_shipped_spec
from mjcf.writer import mjcf_xml, save_mjcf
from zrp.packages import DISTRIBUTION

#: The distribution this ``mjcf`` belongs to (a generic name: see :mod:`zrp.packages`).
__distribution__ = DISTRIBUTION
from zrp.units import LENGTH_UNITS, metres_per_unit

__all__ = [
    "INERTIA_MODELS",
    "LENGTH_UNITS",
    "ArmDynamics",
    "BodyInertia",
    "BuiltArm",
    "MJCFCompileError",
    "MJCFImportError",
    "MJCFOptions",
    "MJCFOutputError",
    "arm_dynamics",
    "build",
    "build_spec",
    "from_mjcf",
    "gravity_torques",
    "inverse_dynamics_torques",
    "load_mujoco_model",
    "load_shipped",
    "load_shipped_spec",
    "manipulator_from_mujoco",
    "metres_per_unit",
    "mjcf_xml",
    "mode_terms",
    "puma560_inertias",
    "rod_inertias",
    "save_mjcf",
]
