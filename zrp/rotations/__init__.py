"""Rotations, the bottom package every other one imports for SO(3).

* :mod:`zrp.rotations.rodrigues`: Euler-Rodrigues parameters (e0, e1, e2, e3), scalar first:
  composition, conjugate, rotation of vectors, conversion to and from matrices, rotation
  vectors and SciPy quaternions, and the paper's eq (15) orientation error.
* :mod:`zrp.rotations.matrices`: skew (cross-product) matrices, exp of a rotation vector, the
  left Jacobian of SO(3), and the angle between two frames.
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "left_jacobian": "zrp.rotations.matrices",
    "matrix_from_rotvec": "zrp.rotations.matrices",
    "rotation_angle": "zrp.rotations.matrices",
    "skew": "zrp.rotations.matrices",
    "er_angle": "zrp.rotations.rodrigues",
    "er_conjugate": "zrp.rotations.rodrigues",
    "er_delta_r": "zrp.rotations.rodrigues",
    "er_from_axis_angle": "zrp.rotations.rodrigues",
    "er_from_matrix": "zrp.rotations.rodrigues",
    "er_from_rotvec": "zrp.rotations.rodrigues",
    "er_from_scipy_quat": "zrp.rotations.rodrigues",
    "er_identity": "zrp.rotations.rodrigues",
    "er_multiply": "zrp.rotations.rodrigues",
    "er_rotate": "zrp.rotations.rodrigues",
    "matrix_from_er": "zrp.rotations.rodrigues",
    "rotvec_from_er": "zrp.rotations.rodrigues",
    "scipy_quat_from_er": "zrp.rotations.rodrigues",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.rotations.matrices import left_jacobian as left_jacobian
    from zrp.rotations.matrices import matrix_from_rotvec as matrix_from_rotvec
    from zrp.rotations.matrices import rotation_angle as rotation_angle
    from zrp.rotations.matrices import skew as skew
    from zrp.rotations.rodrigues import er_angle as er_angle
    from zrp.rotations.rodrigues import er_conjugate as er_conjugate
    from zrp.rotations.rodrigues import er_delta_r as er_delta_r
    from zrp.rotations.rodrigues import er_from_axis_angle as er_from_axis_angle
    from zrp.rotations.rodrigues import er_from_matrix as er_from_matrix
    from zrp.rotations.rodrigues import er_from_rotvec as er_from_rotvec
    from zrp.rotations.rodrigues import er_from_scipy_quat as er_from_scipy_quat
    from zrp.rotations.rodrigues import er_identity as er_identity
    from zrp.rotations.rodrigues import er_multiply as er_multiply
    from zrp.rotations.rodrigues import er_rotate as er_rotate
    from zrp.rotations.rodrigues import matrix_from_er as matrix_from_er
    from zrp.rotations.rodrigues import rotvec_from_er as rotvec_from_er
    from zrp.rotations.rodrigues import scipy_quat_from_er as scipy_quat_from_er
