"""Kinematic playback through MuJoCo and its consistency check against ZRP direct kinematics."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf import BuiltArm, MJCFOptions, build, metres_per_unit
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, forward_kinematics
from zrp.model.manipulator import Manipulator
from zrp.rotations import rotation_angle

__all__ = [
    "ConsistencyReport",
    "SitePoses",
    "as_built",
    "consistency_check",
    "kinematic_playback",
]



def as_built(arm: BuiltArm | Manipulator, options: MJCFOptions | None = None) -> BuiltArm:
    """A :class:`mjcf.BuiltArm`: passed through, or built from a :class:`zrp.Manipulator`."""
    if isinstance(arm, BuiltArm):
        return arm
    if isinstance(arm, Manipulator):
        return build(arm, options)
    raise InputError(f"model: expected a zrp.Manipulator or a mjcf.BuiltArm, got "
                     f"{type(arm).__name__}")


@dataclass(frozen=True, eq=False)
class SitePoses:
    """End-effector site poses along a joint trajectory, read from MuJoCo.

    Attributes:
        position: site position p, model length unit, shape (N, 3).
        frame: site frame = hand frame, columns (u_t x u_a, u_t, u_a), shape (N, 3, 3).
        length_unit: unit of ``position``.
    """

    position: F64
    frame: F64
    length_unit: str

    def __post_init__(self) -> None:
        p, f = np.asarray(self.position), np.asarray(self.frame)
        if p.ndim != 2 or p.shape[1] != 3 or f.shape != (p.shape[0], 3, 3):
            raise InputError(f"position/frame: expected shapes (N, 3) and (N, 3, 3), got "
                             f"{p.shape} and {f.shape}")

    @property
    def axial(self) -> F64:
        """u_a, shape (N, 3)."""
        return self.frame[:, :, 2]

    @property
    def transverse(self) -> F64:
        """u_t, shape (N, 3)."""
        return self.frame[:, :, 1]


def kinematic_playback(arm: BuiltArm | Manipulator, q: ArrayLike) -> SitePoses:
    """Set qpos to each row of ``q`` and read the end-effector site (``mj_kinematics``).

    Args:
        arm: a built arm, or a ZRP model (built with default options).
        q: joint values, rad (model length unit for prismatic joints), shape (N, n) or (n,).

    Returns:
        :class:`SitePoses` with N poses (1 for a single configuration).
    """
    arm = as_built(arm)
    q = check_q(arm.manipulator, q)
    q2 = np.atleast_2d(q)
    if q2.ndim != 2:
        raise InputError(f"q: expected shape (N, {arm.manipulator.n}), got {q.shape}")
    qpos = arm.qpos(q2)
    data = mujoco.MjData(arm.model)
    pos = np.empty((len(q2), 3))
    frame = np.empty((len(q2), 3, 3))
    for i, row in enumerate(qpos):
        data.qpos[arm.qpos_adr] = row
        mujoco.mj_kinematics(arm.model, data)
        pos[i] = data.site_xpos[arm.site_id]
        frame[i] = data.site_xmat[arm.site_id].reshape(3, 3)
    return SitePoses(pos / arm.scale, frame, arm.manipulator.length_unit)


@dataclass(frozen=True, eq=False)
class ConsistencyReport:
    """MuJoCo site poses against ZRP direct kinematics along a trajectory.

    Attributes:
        position_error: |p_mujoco - p_zrp| per step, model length unit, shape (N,).
        orientation_error: angle between the two hand frames per step, rad, shape (N,).
        length_unit: unit of ``position_error``.
        model_name: the model checked.
    """

    position_error: F64
    orientation_error: F64
    length_unit: str
    model_name: str

    def __post_init__(self) -> None:
        dp, dr = np.asarray(self.position_error), np.asarray(self.orientation_error)
        if dp.ndim != 1 or dr.shape != dp.shape or len(dp) == 0:
            raise InputError(f"position_error/orientation_error: expected two equal shapes "
                             f"(N,) with N >= 1, got {dp.shape} and {dr.shape}")
        metres_per_unit(self.length_unit)

    @property
    def max_position_error(self) -> float:
        """Largest position error, model length unit."""
        return float(np.max(self.position_error))

    @property
    def max_position_error_mm(self) -> float:
        """Largest position error, mm."""
        return self.max_position_error * metres_per_unit(self.length_unit) * 1e3

    @property
    def max_orientation_error(self) -> float:
        """Largest orientation error, rad."""
        return float(np.max(self.orientation_error))

    def passed(self, position_tol_mm: float = 1e-9, orientation_tol_rad: float = 1e-12) -> bool:
        """Whether both maxima are within the bounds (defaults: 1e-9 mm, 1e-12 rad)."""
        return (self.max_position_error_mm <= position_tol_mm
                and self.max_orientation_error <= orientation_tol_rad)

    def summary(self) -> str:
        return (f"{self.model_name}: {len(self.position_error)} poses, max position error "
                f"{self.max_position_error_mm:.3g} mm, max orientation error "
                f"{self.max_orientation_error:.3g} rad")


def consistency_check(model: Manipulator, q: ArrayLike, arm: BuiltArm | None = None
                      ) -> ConsistencyReport:
    """Compare MuJoCo's end-effector site with :func:`zrp.forward_kinematics`.

    Args:
        model: the ZRP model (nominal or perturbed).
        q: joint values, shape (N, n) or (n,).
        arm: a built arm of ``model``; built with default options when None.
    """
    if arm is None:
        arm = build(model)
    elif arm.manipulator is not model:
        raise InputError("arm: was built from a different model than `model`")
    poses = kinematic_playback(arm, q)
    fk = forward_kinematics(model, np.atleast_2d(check_q(model, q)))
    dp = np.linalg.norm(poses.position - fk.position, axis=-1)
    dr = rotation_angle(poses.frame, fk.hand_frame)
    return ConsistencyReport(dp, dr, model.length_unit, model.name)
