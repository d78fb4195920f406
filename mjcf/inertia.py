"""Mass properties for the MJCF models: PUMA 560 literature values and a generic rod model.

PUMA 560 values
---------------
Link masses m, centres of mass r and principal inertias (about the centre of mass) are those of
Armstrong, Khatib & Burdick (1986), "The explicit dynamic model and inertial parameters of the
PUMA 560 arm", Proc. IEEE ICRA, pp. 510-518, as tabulated in the standard-DH link frames by
Corke & Armstrong-Hélouvry (1994), "A search for consensus among model parameters reported for
the PUMA 560 robot", Proc. IEEE ICRA, pp. 1608-1613 (also the Robotics Toolbox ``Puma560``).
The reflected motor inertias ``Jm * G**2`` (same sources) become MuJoCo joint ``armature``.

Armstrong et al. give no mass for link 1 (it does not enter the dynamics: its centre of mass is
on the vertical joint-1 axis) and only its inertia about that axis (0.35 kg m^2); we use a
nominal 1 g mass and split the other two moments equally so the tensor is physical. Link 3's
published principal moments violate the triangle inequality; see :func:`_physical`.

Mapping into the paper's zero reference position: the paper's Table 1 PUMA is the Corke PUMA at
q = 0 turned by pi about the base x axis (the forearm and the tool hang down). The standard-DH
link frame axes (x_k, y_k, z_k) in the paper's base frame at q = 0 are listed in ``_DH_AXES``
below, derived from the DH twists (alpha = pi/2, 0, -pi/2, pi/2, -pi/2, 0). Each frame's origin
is placed where the paper's geometry has it: link 2's on the elbow axis in the plane through the
joint-1 axis, links 3-6 at the elbow and wrist points. The small a3/d3 differences between the
real PUMA 560 and the paper's simplified geometry (254 mm shoulder offset, a3 = 0) are ignored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator

__all__ = ["INERTIA_MODELS", "BodyInertia", "puma560_inertias", "rod_inertias"]

INERTIA_MODELS = ("none", "rods", "puma560")



@dataclass(frozen=True, eq=False)
class BodyInertia:
    """Mass properties of one moving body, in its MuJoCo body frame (world-aligned at q = 0).

    Attributes:
        mass: kg.
        com: centre of mass relative to the body origin (the point on joint k), m, shape (3,).
        inertia: inertia tensor about the centre of mass, kg m^2, shape (3, 3).
        armature: reflected rotor inertia of the joint, kg m^2 (or kg for prismatic joints).
    """

    mass: float
    com: F64
    inertia: F64
    armature: float = 0.0

    def __post_init__(self) -> None:
        com = np.asarray(self.com, dtype=float)
        inertia = np.asarray(self.inertia, dtype=float)
        if not (np.isfinite(self.mass) and self.mass > 0):
            raise InputError(f"mass: expected a positive number of kg, got {self.mass!r}")
        if com.shape != (3,) or not np.all(np.isfinite(com)):
            raise InputError(f"com: expected 3 finite numbers (m), got {self.com!r}")
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T):
            raise InputError("inertia: expected a symmetric 3x3 matrix (kg m^2)")
        object.__setattr__(self, "com", com)
        object.__setattr__(self, "inertia", inertia)

    @property
    def fullinertia(self) -> list[float]:
        """MuJoCo's ``fullinertia`` order: Ixx, Iyy, Izz, Ixy, Ixz, Iyz."""
        i = self.inertia
        return [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]


# ---- PUMA 560 ------------------------------------------------------------------------------
# (mass kg, r in DH frame m, principal inertias Ixx Iyy Izz in DH frame kg m^2, Jm kg m^2, G)
_PUMA560 = (
    (0.0, (0.0, 0.0, 0.0), (0.0, 0.35, 0.0), 200e-6, -62.6111),
    (17.4, (-0.3638, 0.006, 0.2275), (0.13, 0.524, 0.539), 200e-6, 107.815),
    (4.8, (-0.0203, -0.0141, 0.070), (0.066, 0.086, 0.0125), 200e-6, -53.7063),
    (0.82, (0.0, 0.019, 0.0), (1.8e-3, 1.3e-3, 1.8e-3), 33e-6, 76.0364),
    (0.34, (0.0, 0.0, 0.0), (0.3e-3, 0.4e-3, 0.3e-3), 33e-6, 71.923),
    (0.09, (0.0, 0.0, 0.032), (0.15e-3, 0.15e-3, 0.04e-3), 33e-6, 76.686),
)
_X, _Y, _Z = np.eye(3)
# Columns x_k, y_k, z_k of each standard-DH link frame in the paper's base frame at q = 0.
_DH_AXES = (
    np.column_stack([_X, -_Z, _Y]),
    np.column_stack([_X, -_Z, _Y]),
    np.column_stack([_X, -_Y, -_Z]),
    np.column_stack([_X, -_Z, _Y]),
    np.column_stack([_X, -_Y, -_Z]),
    np.column_stack([_X, -_Y, -_Z]),
)
_LINK1_MASS = 1e-3  # kg; not given by Armstrong et al., dynamically irrelevant (see above)


def _physical(principal: tuple[float, float, float]) -> F64:
    """Raise the smallest principal moment to satisfy the triangle inequality if needed.

    Link 3's published moments (0.066, 0.086, 0.0125) violate A + B >= C, impossible for a
    rigid body (and refused by MuJoCo); the smallest becomes 0.086 - 0.066 = 0.020 kg m^2.
    """
    i = np.array(principal, dtype=float)
    order = np.argsort(i)
    lo, mid, hi = order
    if i[lo] + i[mid] < i[hi]:
        i[lo] = i[hi] - i[mid]
    return i


def puma560_inertias(model: Manipulator, metres_per_unit: float) -> list[BodyInertia]:
    """PUMA 560 literature mass properties for the six moving bodies of a 6R PUMA-type model.

    Args:
        model: a six-revolute-joint model laid out like the paper's Table 1 (nominal or
            perturbed); the DH origin of link 2 is found from its geometry.
        metres_per_unit: the model's length unit in metres.

    Returns:
        six :class:`BodyInertia`, body frames world-aligned at q = 0.
    """
    if model.n != 6 or model.prismatic.any():
        raise InputError(f"inertia='puma560': needs a 6-revolute-joint PUMA-type model, got "
                         f"{model!r}; use inertia='rods' for other arms")
    bodies = np.asarray(model.bodies) * metres_per_unit
    points = np.cumsum(bodies[:-1], axis=0)  # point on joint k, world, m
    out = []
    for k, (mass, r, inertia, jm, gear) in enumerate(_PUMA560):
        axes = _DH_AXES[k]
        if k == 1:
            # link 2's DH origin: on the elbow (joint 3) axis, in the plane through the joint-1
            # axis perpendicular to the elbow axis.
            u3 = np.asarray(model.axes[2])
            elbow = points[2]
            s = -float(u3 @ (elbow - points[0]))
            origin = elbow + s * u3
        elif k == 0:
            origin = points[0]
        else:
            origin = points[2] if k == 2 else points[3]
        com_world = origin + axes @ np.asarray(r)
        tensor = axes @ np.diag(_physical(inertia)) @ axes.T
        if k == 0:
            izz = inertia[1]
            tensor = axes @ np.diag([izz / 2, izz, izz / 2]) @ axes.T
            mass = _LINK1_MASS
        out.append(BodyInertia(mass=mass, com=com_world - points[k], inertia=tensor,
                               armature=jm * gear**2))
    return out


def _shift(i: F64, m: float, c: F64) -> F64:
    """Parallel-axis theorem: inertia about a point at -c from the centre of mass."""
    return i + m * (float(c @ c) * np.eye(3) - np.outer(c, c))


def rod_inertias(model: Manipulator, metres_per_unit: float, linear_density: float = 10.0,
                 joint_mass: float = 1.0, radius: float = 0.03) -> list[BodyInertia]:
    """Generic mass properties: body k carries link b_{k+1} as a uniform solid rod.

    Args:
        linear_density: kg per metre of link.
        joint_mass: kg of a point-like motor at each joint (a small sphere of ``radius``).
        radius: rod and motor radius, m.

    Returns:
        n :class:`BodyInertia`, body frames world-aligned at q = 0.
    """
    bodies = np.asarray(model.bodies) * metres_per_unit
    out = []
    for k in range(model.n):
        b = bodies[k + 1]
        length = float(np.linalg.norm(b))
        m_rod = linear_density * length
        d = b / length if length > 0 else np.zeros(3)
        eye = np.eye(3)
        i_rod = m_rod * (length**2 / 12 + radius**2 / 4) * (eye - np.outer(d, d)) \
            + m_rod * radius**2 / 2 * np.outer(d, d)
        com_rod = b / 2
        m_motor = joint_mass
        i_motor = 0.4 * m_motor * radius**2 * eye
        mass = m_rod + m_motor
        com = m_rod * com_rod / mass
        tensor = _shift(i_rod, m_rod, com_rod - com) + _shift(i_motor, m_motor, -com)
        out.append(BodyInertia(mass=mass, com=com, inertia=tensor, armature=0.05))
    return out
