"""Positional and rotational deviations of a perturbed arm along a joint trajectory, eqs (15)-(17).

The joint trajectory q(t) comes from the *nominal* model's inverse kinematics. The desired
pose is the nominal model's direct kinematics of q(t); the actual pose is the perturbed model's
direct kinematics of the same joint values (the controller does not know the errors). Then

* delta_p = ||p_a - p_d|| (eq 17), in the model's length unit;
* the error rotation E_eps = E_a * conj(E_d) (base frame) has angle theta_eps, and the paper's
  rotational deviation is delta_R = sqrt(4 (1 - e0^2 + e.e)) (eqs 15-16), which equals
  2 sqrt(2) sin(theta_eps / 2), about sqrt(2) theta_eps. Both are reported: ``delta_r`` as the
  paper defines it (dimensionless) and ``angle_rad`` = theta_eps.

**Rounding.** Written literally, eq (15) subtracts e0^2 ~ 1 from 1, so it cannot resolve
deviations below ~sqrt(4 * 2^-52) ~ 3e-8: an exact-zero error rotation composed in double
precision comes out as 0, 3e-8, 6e-8, 7e-8... The paper's 0 % row of Table 3, 5.96E-8, is
2^-24 exactly, i.e. this rounding floor. Here delta_R is evaluated in the algebraically
identical form sqrt(8 e.e) = 2 sqrt(2) ||e|| (using e0^2 + e.e = 1), which has no floor;
:func:`delta_r_literal` keeps the literal formula for the comparison.

With a zero perturbation both are exactly zero; the paper's 0 % rows (1.07E-8 mm, 5.96E-8)
are instead the error of its inverse kinematics against the commanded circle, which
:mod:`zrp.paper.example` reports from the IK result.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.manufacturing.perturb import Perturbation
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import er_angle, er_conjugate, er_multiply, rotvec_from_er

__all__ = [
    "Deviation",
    "check_times",
    "delta_r_eq15",
    "delta_r_literal",
    "pose_deviation",
    "trajectory_deviation",
]



def check_times(t: ArrayLike | None, n_points: int, name: str = "t") -> F64:
    """Sample times (s), shape (N,), finite and non-decreasing; 0..N-1 when ``t`` is None."""
    if t is None:
        return np.arange(n_points, dtype=float)
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected numbers (s), got {type(t).__name__}") from exc
    if arr.shape != (n_points,):
        raise InputError(f"{name}: expected shape ({n_points},) (one time per joint sample), got "
                         f"{arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite times")
    if np.any(np.diff(arr) < 0):
        raise InputError(f"{name}: expected non-decreasing times")
    return arr


def delta_r_eq15(e_err: ArrayLike) -> F64:
    """Eqs (15)-(16) in rounding-free form: sqrt(8 e.e) = 2 sqrt(2) |sin(theta/2)|.

    Args:
        e_err: unit Euler-Rodrigues parameters of the error rotation, shape (..., 4).

    Returns:
        delta_R, shape (...), dimensionless (about sqrt(2) theta for small theta in rad).
    """
    e = np.asarray(e_err, dtype=float)
    return np.sqrt(8.0) * np.linalg.norm(e[..., 1:], axis=-1)


def delta_r_literal(e_err: ArrayLike) -> F64:
    """Eq (15) exactly as printed, sqrt(4 (1 - e0^2 + e.e)), shape (..., 4) -> (...).

    Has a rounding floor of ~3e-8 (see the module docstring); prefer :func:`delta_r_eq15`.
    """
    e = np.asarray(e_err, dtype=float)
    ee = np.sum(e[..., 1:] ** 2, axis=-1)
    return np.sqrt(np.maximum(4.0 * (1.0 - e[..., 0] ** 2 + ee), 0.0))


@dataclass(frozen=True, eq=False)
class Deviation:
    """Deviations of the actual from the desired end-effector pose at N samples.

    Attributes:
        t: sample times (s), shape (N,).
        dp: p_a - p_d, shape (N, 3), length unit.
        rotvec: rotation vector of E_a * conj(E_d) (rad, base frame), shape (N, 3).
        delta_p: eq (17), ||dp||, shape (N,), length unit.
        delta_r: eq (15) as the paper defines it, 2 sqrt(2) sin(theta/2), shape (N,).
        angle_rad: theta_eps, the angle of the error rotation (rad), shape (N,).
        unit: the length unit, e.g. "mm".
        convention: the sign(0) convention of the perturbation ("" when not from eqs 8-12).
    """

    t: F64
    dp: F64
    rotvec: F64
    delta_p: F64
    delta_r: F64
    angle_rad: F64
    unit: str = "mm"
    convention: str = ""

    def __post_init__(self) -> None:
        n = self.t.shape[0] if np.ndim(self.t) == 1 else -1
        for name, shape in (("dp", (n, 3)), ("rotvec", (n, 3)), ("delta_p", (n,)),
                            ("delta_r", (n,)), ("angle_rad", (n,))):
            if np.shape(getattr(self, name)) != shape:
                raise InputError(f"Deviation.{name}: expected shape {shape}, got "
                                 f"{np.shape(getattr(self, name))}")

    @property
    def max_delta_p(self) -> float:
        """max_t delta_p (length unit)."""
        return float(np.max(self.delta_p))

    @property
    def max_delta_r(self) -> float:
        """max_t delta_R of eq (15) (dimensionless, as the paper defines it)."""
        return float(np.max(self.delta_r))

    @property
    def max_angle_rad(self) -> float:
        """max_t theta_eps (rad)."""
        return float(np.max(self.angle_rad))

    def summary(self) -> dict[str, float | str]:
        return {
            f"max_delta_p_{self.unit}": self.max_delta_p,
            "max_delta_R_eq15": self.max_delta_r,
            "max_angle_rad": self.max_angle_rad,
            "sign_convention": self.convention,
        }


def pose_deviation(nominal: Manipulator, actual: Manipulator, q: ArrayLike,
                   t: ArrayLike | None = None, *, q_offset: ArrayLike | None = None,
                   convention: str = "") -> Deviation:
    """Deviations of ``actual`` from ``nominal`` at the same joint values.

    Args:
        nominal, actual: models with the same number of joints.
        q: joint values from the nominal inverse kinematics, shape (N, n) (rad / length unit).
        t: sample times (s), shape (N,); default 0..N-1.
        q_offset: joint zero offsets of the actual arm, shape (n,), added to q for ``actual``.
    """
    if actual.n != nominal.n:
        raise InputError(f"actual: has {actual.n} joints, the nominal model {nominal.n}")
    q = check_q(nominal, q)
    if q.ndim != 2:
        raise InputError(f"q: expected shape (N, {nominal.n}) (a joint trajectory), got {q.shape}")
    t = check_times(t, q.shape[0])
    qa = q if q_offset is None else q + check_q(nominal, q_offset, "q_offset")
    p_d, e_d = end_effector_pose(nominal, q)
    p_a, e_a = end_effector_pose(actual, qa)
    dp = p_a - p_d
    e_err = er_multiply(e_a, er_conjugate(e_d))
    return Deviation(
        t=t,
        dp=dp,
        rotvec=rotvec_from_er(e_err),
        delta_p=np.linalg.norm(dp, axis=-1),  # eq (17)
        delta_r=delta_r_eq15(e_err),  # eqs (15)-(16)
        angle_rad=er_angle(e_err),
        unit=nominal.length_unit,
        convention=convention,
    )


def trajectory_deviation(nominal: Manipulator, perturbation: Perturbation, q: ArrayLike,
                         t: ArrayLike | None = None) -> Deviation:
    """Deviations caused by a :class:`~zrp.manufacturing.Perturbation` (eqs 8-12) along q(t).

    Args:
        q: nominal inverse-kinematics joint values, shape (N, n).
        t: sample times (s), shape (N,).
    """
    if not isinstance(perturbation, Perturbation):
        raise InputError(f"perturbation: expected a zrp.manufacturing.perturb.Perturbation, got "
                         f"{type(perturbation).__name__}")
    return pose_deviation(nominal, perturbation.apply(nominal), q, t,
                          convention=perturbation.convention)
