"""What the dynamic gap needs of an arm model: the small interface the core defines and
:class:`mjcf.arm.Arm` implements with MuJoCo (``mj_inverse``).

The diagnosis never sees MuJoCo: it asks an arm for its joints, its moving bodies and their
inertial parameters (eq. R1 of :mod:`zrp.gap.dynamics.inertia`), the model's own joint
friction, damping and armature, and the joint torques of the model along states (inverse
dynamics, gravity, the inertial regressor). Any object with these members will do (a test
double, another physics engine).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64

__all__ = ["Attachment", "DynamicArm"]


@dataclass(frozen=True)
class Attachment:
    """A part the model carries rigidly on its last link (a hand, a gripper, a tool, a
    flange with mass): something that may not be mounted on the real arm.

    Attributes:
        name: the part's first link with mass (e.g. ``panda_hand``).
        phi: its inertial parameters (eq. R1) in the tool body's frame, with every link
            attached to it (e.g. the fingers), shape (10,).
        members: the names of the links it lumps.
    """

    name: str
    phi: F64
    members: tuple[str, ...] = ()

    @property
    def mass(self) -> float:
        return float(self.phi[0])


@runtime_checkable
class DynamicArm(Protocol):
    """An arm model for the dynamic gap; dof k is logged joint k.

    Attributes:
        name: for reports.
        tool_body: id of the body carrying the tool (where a payload sits).
        tool_point: the payload point in the tool body's frame, m, shape (3,).
        attachments: the parts the model carries rigidly on the tool body (may be empty),
            each with its inertial parameters in the tool body's frame.
    """

    name: str
    tool_body: int
    tool_point: F64
    attachments: tuple[Attachment, ...]

    @property
    def n(self) -> int:
        """The number of joints."""
        ...

    @property
    def joint_names(self) -> list[str]:
        """The joints' names in the model, in dof order."""
        ...

    def moving_bodies(self) -> list[int]:
        """Ids of the bodies whose inertias enter the torques, in a fixed order."""
        ...

    def body_name(self, b: int) -> str:
        """The name of body ``b`` (for reports)."""
        ...

    def body_params(self, b: int) -> F64:
        """phi_b of body ``b`` in the model (eq. R1), shape (10,)."""
        ...

    def joint_terms(self) -> tuple[F64, F64, F64]:
        """The model's own Coulomb friction (N m), viscous damping (N m s/rad) and armature
        (kg m^2) per joint, each shape (n,)."""
        ...

    def position_limits(self) -> tuple[F64, F64]:
        """Lower and upper joint limits, rad or m, each (n,); -inf/+inf where none."""
        ...

    def velocity_limits(self) -> F64:
        """Largest joint speed the model allows, rad/s (m/s), shape (n,); inf where none is
        known."""
        ...

    def revolute(self) -> NDArray[np.bool_]:
        """Which joints are hinges (rad); the others slide (m), shape (n,)."""
        ...

    def torque_limits(self) -> F64:
        """Largest joint torque the model allows, N m (N), shape (n,); inf where none."""
        ...

    def inverse_dynamics(self, q: F64, qd: F64, qdd: F64) -> F64:
        """The model's joint torques along the states, (S, n) each, with its friction."""
        ...

    def gravity_torques(self, q: F64) -> F64:
        """Gravity's joint torques at ``q``, shape (S, n)."""
        ...

    def regressor(self, q: F64, qd: F64, qdd: F64, bodies: Iterable[int] | None = None
                  ) -> tuple[F64, list[tuple[int, str]]]:
        """Y (eq. R2) of ``bodies`` (default: the moving bodies), shape (S, n, 10 B), and the
        (body, parameter) of each column."""
        ...
