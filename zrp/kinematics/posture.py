"""Inverse kinematics that respects the robot: joint limits, redundancy resolved by a rest
posture, single-pose IK, singularities named as such.

At every point the joint values solve

    minimise  f(q) = 1/2 sum_k w_k (q_k - r_k)^2 + kappa/2 sum_k v_k(q)^2      (P1)
    subject to the pose (or position) of the end effector = the desired one,

where r is the rest posture (by default the start configuration), and v_k(q) is how far q_k
has entered the margin band inside its limits (0 elsewhere): a stiff penalty that pushes the
self-motion away from the limits. (P1) is solved by sequential quadratic programming: per
iteration the constraint is linearised with the eq (7) Jacobian J (rows scaled as in
:mod:`.ik`) and the KKT system

    [ H   J^T ] [ dq     ]   [ -grad f ]
    [ J   0   ] [ lambda ] = [  e      ]                                          (P2)

(H the diagonal Hessian of f, e the pose error) is solved for the step dq; the fixed point is
the minimiser of f on the self-motion manifold, where the null-space component of grad f
vanishes. Because the solution depends on the point and not on the path to it, a closed path
returns the arm to its start (the minimum-norm rate integration of :mod:`.ik` does not).
Afterwards the joint values are checked against the limits: a path that needs a joint beyond
them is a :class:`~zrp.errors.JointLimitError` naming the joint and the time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError, JointLimitError, SingularityError, UnreachableError
from zrp.kinematics.forward import check_q, end_effector_pose, jacobian
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import er_conjugate, er_multiply, rotvec_from_er

__all__ = ["PoseSolution", "Posture", "check_limits_along", "pose_error", "solve_pose"]


#: Penalty stiffness kappa in (P1), relative to the rest weights.
KAPPA = 1e4


@dataclass(frozen=True)
class Posture:
    """The secondary objective of (P1): rest posture r (shape (n,), rad or length unit), weights
    w (shape (n,); default 1 for revolute, 1/L^2 for prismatic joints, L the characteristic
    length) and the limit margin as a fraction of each joint's range (default 5 %)."""

    rest: F64
    weights: F64
    margin: float = 0.05

    @classmethod
    def build(cls, model: Manipulator, rest: ArrayLike, weights: ArrayLike | None = None,
              margin: float = 0.05) -> Posture:
        r = np.array(check_q(model, rest, "rest"), dtype=float)
        if r.shape != (model.n,):
            raise InputError(f"rest: expected shape ({model.n},), got {r.shape}")
        if weights is None:
            w = np.where(model.prismatic, 1.0 / model.characteristic_length ** 2, 1.0)
        else:
            w = np.array(weights, dtype=float)
            if w.shape != (model.n,) or not np.all(np.isfinite(w)) or np.any(w < 0):
                raise InputError(f"weights: expected {model.n} finite numbers >= 0, got "
                                 f"{np.asarray(weights).tolist()}")
        if not 0 <= margin < 0.5:
            raise InputError(f"margin: expected a fraction in [0, 0.5), got {margin!r}")
        return cls(r, w, float(margin))

    def band(self, model: Manipulator) -> tuple[F64, F64]:
        """Inner edges of the margin band, shape (n,) each (+-inf without limits)."""
        span = np.where(np.isfinite(model.upper - model.lower), model.upper - model.lower, 0.0)
        return model.lower + self.margin * span, model.upper - self.margin * span

    def gradient(self, model: Manipulator, q: F64) -> tuple[F64, F64]:
        """(grad f, diagonal of the Hessian of f) of (P1), shape (n,) each."""
        lo, hi = self.band(model)
        v = np.minimum(q - lo, 0.0) + np.maximum(q - hi, 0.0)
        kappa = KAPPA * np.maximum(self.weights, 1e-12)
        return (self.weights * (q - self.rest) + kappa * v,
                self.weights + kappa * (v != 0) + 1e-12)


def pose_error(model: Manipulator, q: F64, pd: F64, erd: F64 | None) -> tuple[F64, F64]:
    """(error e in the rows of eq 7: [rotation vector of R_d R^T; p_d - p], shape (6,) or (3,)
    without an orientation, and the Jacobian rows, shape (6, n) or (3, n))."""
    p, er = end_effector_pose(model, q)
    jac = jacobian(model, q)
    if erd is None:
        return pd - p, jac[3:]
    rot = rotvec_from_er(er_multiply(erd, er_conjugate(er)))
    return np.concatenate([rot, pd - p]), jac


def _scales(model: Manipulator, m: int) -> F64:
    """Row scales making eq (7)'s rows comparable (position rows / L)."""
    inv_l = 1.0 / model.characteristic_length
    return np.concatenate([np.ones(m - 3), np.full(3, inv_l)])


def sqp(model: Manipulator, q: F64, pd: F64, erd: F64 | None, posture: Posture,
        max_iter: int = 60, tol: float = 1e-13, max_step: float = 0.3
        ) -> tuple[F64, int, F64, F64]:
    """Solve (P1) from ``q`` by the KKT iteration (P2). Returns (q, iterations, error e,
    scaled Jacobian at q)."""
    n = model.n
    it = 0
    while it < max_iter:
        it += 1
        e, jac = pose_error(model, q, pd, erd)
        s = _scales(model, e.size)
        js = jac * s[:, None]
        g, h = posture.gradient(model, q)
        kkt = np.zeros((n + e.size, n + e.size))
        kkt[:n, :n] = np.diag(h)
        kkt[:n, n:] = js.T
        kkt[n:, :n] = js
        sol = np.linalg.lstsq(kkt, np.concatenate([-g, e * s]), rcond=1e-14)[0]
        dq = sol[:n]
        big = np.max(np.abs(dq))
        q = q + (dq * (max_step / big) if big > max_step else dq)
        if big < tol * max(1.0, float(np.max(np.abs(q)))):
            break
    e, jac = pose_error(model, q, pd, erd)
    return q, it, e, jac * _scales(model, e.size)[:, None]


@dataclass(frozen=True, eq=False)
class PoseSolution:
    """Single-pose IK: q (shape (n,)), the remaining position error (length unit) and
    orientation error (rad, 0 for a position target), SQP iterations, and the smallest
    singular value of the scaled Jacobian at q (0 at a singularity)."""

    q: F64
    position_error: float
    orientation_error: float
    iterations: int
    min_singular_value: float

    def summary(self) -> dict[str, Any]:
        return {"q": self.q.tolist(), "position_error": self.position_error,
                "orientation_error_rad": self.orientation_error,
                "iterations": self.iterations, "min_singular_value": self.min_singular_value}


def _within_reach(model: Manipulator, p: F64) -> tuple[bool, float, float]:
    reach = float(np.sum(np.linalg.norm(model.bodies[1:], axis=1)))
    dist = float(np.linalg.norm(p - model.bodies[0]))
    return bool(model.prismatic.any() or dist <= reach * (1 + 1e-12)), dist, reach


def check_limits_along(model: Manipulator, t: F64, q: F64, tol: float = 1e-9) -> None:
    """Raise :class:`JointLimitError` naming the first joint and time where ``q`` (shape
    (N, n)) leaves the model's limits by more than ``tol``."""
    over = (q < model.lower - tol) | (q > model.upper + tol)
    if not over.any():
        return
    i, k = np.argwhere(over)[0]
    unit = model.length_unit if model.prismatic[k] else "rad"
    raise JointLimitError(
        f"joint {k + 1} ({model.joint_names[k]}) leaves its limits [{model.lower[k]:.6g}, "
        f"{model.upper[k]:.6g}] {unit} at t = {t[i]:.6g} s (q = {q[i, k]:.6g} {unit}; "
        f"{int(over[:, k].sum())} samples out): the path needs more than the joint allows")


def solve_pose(model: Manipulator, position: ArrayLike, er: ArrayLike | None = None, *,
               q0: ArrayLike, rest: ArrayLike | None = None, margin: float = 0.05,
               tol: float | None = None) -> PoseSolution:
    """Joint values reaching ``position`` (shape (3,), length unit) and, if given, the hand
    rotation ``er`` (Euler-Rodrigues, relative to the zero reference, like
    :func:`end_effector_pose`), closest to ``rest`` (default ``q0``) among the solutions, and
    within the joint limits.

    Raises:
        UnreachableError: the target is beyond the arm's reach.
        SingularityError: within reach, but the solver stops at a singularity (rank-deficient
            Jacobian) away from the target.
        JointLimitError: the only solution found needs a joint beyond its limits.
    """
    q0 = np.array(check_q(model, q0, "q0"), dtype=float)
    pd = np.array(position, dtype=float)
    if pd.shape != (3,) or not np.all(np.isfinite(pd)):
        raise InputError(f"position: expected 3 finite numbers, got {np.asarray(position)}")
    erd = None if er is None else np.asarray(er, dtype=float) / np.linalg.norm(er)
    ok, dist, reach = _within_reach(model, pd)
    if not ok:
        raise UnreachableError(f"position: {np.round(pd, 6).tolist()} is {dist:.6g} "
                               f"{model.length_unit} from joint 1, beyond the arm's reach of "
                               f"{reach:.6g} {model.length_unit}")
    posture = Posture.build(model, q0 if rest is None else rest, margin=margin)
    q, iters, e, js = sqp(model, q0, pd, erd, posture, max_iter=200)
    sv = float(np.linalg.svd(js, compute_uv=False).min())
    ep = float(np.linalg.norm(e[-3:]))
    eo = 0.0 if erd is None else float(np.linalg.norm(e[:3]))
    tol = 1e-9 * model.characteristic_length if tol is None else tol
    if ep > tol or eo > 1e-9:
        if sv < 1e-6:
            raise SingularityError(
                f"the target {np.round(pd, 6).tolist()} is within reach ({dist:.6g} of "
                f"{reach:.6g} {model.length_unit}) but the solver stopped at a singularity "
                f"(smallest singular value {sv:.2g} of the Jacobian at q = "
                f"{np.round(q, 6).tolist()}), {ep:.4g} {model.length_unit} away; start from "
                f"another q0")
        raise UnreachableError(f"the target {np.round(pd, 6).tolist()} was not reached: "
                               f"{ep:.4g} {model.length_unit}, {eo:.3g} rad away after "
                               f"{iters} iterations (the orientation may be out of reach)")
    check_limits_along(model, np.zeros(1), q[None])
    return PoseSolution(q, ep, eo, iters, sv)
