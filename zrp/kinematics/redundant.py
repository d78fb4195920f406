"""Inverse kinematics along a trajectory with a rest-posture objective and joint limits.

At every sample the joint values solve (P1) of :mod:`.posture` (the pose constraint, the
distance to the rest posture, a penalty band inside the limits) by the KKT iteration (P2),
started from the previous sample's solution extrapolated linearly. Redundant arms (n > 6 for
the pose, n > 3 for the position) thus move in their null space toward the rest posture, and
a closed path brings them back to where they started. Joint limits are checked on the result:
``limits="error"`` raises :class:`~zrp.errors.JointLimitError` naming the joint and the time,
``"warn"`` emits a :class:`~zrp.errors.TrackingWarning` instead.
"""

from __future__ import annotations

import time
import warnings
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import (
    InputError,
    JointLimitError,
    SingularityError,
    TrackingWarning,
    UnreachableError,
)
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.kinematics.ik import IKResult
from zrp.kinematics.posture import Posture, _within_reach, check_limits_along, sqp
from zrp.kinematics.trajectory import Trajectory
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import er_conjugate, er_multiply, rotvec_from_er

__all__ = ["LIMIT_MODES", "track_posture"]

LIMIT_MODES = ("error", "warn", "ignore")


def at_time(t: float) -> str:
    return f"at t = {t:.6g} s"


def _manipulability(js: F64) -> float:
    return float(np.sqrt(max(np.linalg.det(js @ js.T), 0.0)))


def _stuck(model: Manipulator, t: float, pd: F64, err: float, js: F64, q: F64,
           posture: Posture) -> None:
    """Raise the error that says why the pose at time ``t`` was not reached."""
    ok, dist, reach = _within_reach(model, pd)
    sv = float(np.linalg.svd(js, compute_uv=False).min())
    where = f"at t = {t:.6g} s: point {np.round(pd, 6).tolist()}"
    lo, hi = posture.band(model)
    pressed = np.flatnonzero((q < lo) | (q > hi))
    if ok and pressed.size:
        k = int(pressed[0])
        raise JointLimitError(
            f"joint {k + 1} ({model.joint_names[k]}) would leave its limits [{model.lower[k]:.6g},"
            f" {model.upper[k]:.6g}] {at_time(t)}: held at q = {q[k]:.6g} inside them, the arm "
            f"stays {err:.4g} {model.length_unit} from point {np.round(pd, 6).tolist()}; the path "
            f"needs more than the joint allows")
    if ok and sv < 1e-6:
        raise SingularityError(
            f"cannot follow the path {where} is within reach ({dist:.6g} of {reach:.6g} "
            f"{model.length_unit}) but the arm is at a singularity (smallest singular value "
            f"{sv:.2g}); it stays {err:.4g} {model.length_unit} away")
    raise UnreachableError(f"cannot reach the desired pose {where} stays {err:.4g} "
                           f"{model.length_unit} away (distance {dist:.6g}, reach {reach:.6g} "
                           f"{model.length_unit})")


def _check_options(model: Manipulator, trajectory: Trajectory, q0: ArrayLike, steps: int,
                   task: str | None, limits: str) -> tuple[F64, str]:
    """Validated (q0, task); the task defaults to the pose for six joints or more."""
    if not isinstance(trajectory, Trajectory):
        raise InputError(f"trajectory: expected a zrp Trajectory, got "
                         f"{type(trajectory).__name__}")
    q0 = np.array(check_q(model, q0, "q0"), dtype=float)
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 4:
        raise InputError(f"steps: expected an integer >= 4, got {steps!r}")
    if limits not in LIMIT_MODES:
        raise InputError(f"limits: {limits!r} is unknown; expected one of {LIMIT_MODES}")
    task = task or ("pose" if model.n >= 6 else "position")
    if task not in ("pose", "position"):
        raise InputError(f"task: {task!r} is unknown; expected 'pose' or 'position'")
    return q0, task


def _guess(q: F64, q0: F64, i: int) -> F64:
    """The start of sample ``i``: ``q0``, then the previous solution extrapolated linearly."""
    if i >= 2:
        return 2 * q[i - 1] - q[i - 2]
    return q[0] if i == 1 else q0


def _solve_sample(model: Manipulator, guess: F64, pd: F64, erd: F64 | None, posture: Posture,
                  out: dict[str, F64], i: int) -> tuple[F64, int, F64]:
    """(P2) at one sample from ``guess``: (q, iterations, scaled Jacobian); the guess's drift,
    the errors left, the correction and the manipulability go into row ``i`` of ``out``."""
    p_g, er_g = end_effector_pose(model, guess)
    out["drift_p"][i] = np.linalg.norm(pd - p_g)  # error of the extrapolated guess
    if erd is not None:
        out["drift_o"][i] = np.linalg.norm(rotvec_from_er(er_multiply(erd, er_conjugate(er_g))))
    qi, iters, e, js = sqp(model, guess, pd, erd, posture)
    out["err_p"][i] = np.linalg.norm(e[-3:])
    out["err_o"][i] = np.linalg.norm(e[:3]) if erd is not None else 0.0
    out["corr"][i] = np.linalg.norm(qi - guess)
    out["manip"][i] = _manipulability(js)
    return qi, iters, js


def _limit_notes(model: Manipulator, t: F64, q: F64, limits: str) -> tuple[str, ...]:
    """Check the joint limits along the result: raise, warn (at the caller of
    :func:`track_posture`) and note, or ignore, as ``limits`` says."""
    if limits == "ignore":
        return ()
    try:
        check_limits_along(model, t, q)
    except JointLimitError as exc:
        if limits == "error":
            raise
        warnings.warn(str(exc), TrackingWarning, stacklevel=3)
        return (str(exc),)
    return ()


def track_posture(
    model: Manipulator,
    trajectory: Trajectory,
    q0: ArrayLike,
    steps: int = 1000,
    *,
    rest: ArrayLike | None = None,
    weights: ArrayLike | None = None,
    task: Literal["pose", "position"] | None = None,
    limits: Literal["error", "warn", "ignore"] = "error",
    margin: float = 0.05,
) -> IKResult:
    """Joint trajectory following ``trajectory`` from ``q0``, solving (P1)-(P2) per sample.

    Args:
        model, trajectory, q0, steps, task: as :func:`zrp.track_trajectory` (q0 is first
            projected onto the start pose; the orientation is held at q0's when the
            trajectory has no orientation law).
        rest: rest posture r (default ``q0``); weights: w_k of (P1).
        limits: "error" (default), "warn" or "ignore" when the path needs a joint beyond its
            limits.
        margin: width of the penalty band inside each joint's range, a fraction of it.

    Raises:
        JointLimitError: with ``limits="error"``, names the joint, its limits and the first
            time it is exceeded.
        SingularityError: a point within reach that the arm cannot follow at a singularity.
        UnreachableError: a point beyond reach.
    """
    q0, task = _check_options(model, trajectory, q0, steps, task, limits)
    posture = Posture.build(model, q0 if rest is None else rest, weights, margin)
    started = time.perf_counter()
    t = np.linspace(0.0, trajectory.duration, steps + 1)
    sample = trajectory.evaluate(t)
    if sample.er is not None:
        erd_all = sample.er
    else:
        erd_all = np.tile(end_effector_pose(model, q0)[1], (t.size, 1))
    q = np.zeros((t.size, model.n))
    out = {k: np.zeros(t.size) for k in ("err_p", "err_o", "drift_p", "drift_o", "corr",
                                         "manip")}
    iters = np.zeros(t.size, dtype=np.int64)
    tol_p = 1e-9 * model.characteristic_length
    for i in range(t.size):
        guess = _guess(q, q0, i)
        erd = erd_all[i] if task == "pose" else None
        pd = sample.position[i]
        qi, iters[i], js = _solve_sample(model, guess, pd, erd, posture, out, i)
        if out["err_p"][i] > tol_p or out["err_o"][i] > 1e-9:
            _stuck(model, float(t[i]), pd, float(out["err_p"][i]), js, qi, posture)
        q[i] = qi
    notes = _limit_notes(model, t, q, limits)
    qdot = np.gradient(q, t, axis=0)
    return IKResult(
        t=t, q=q, qdot=qdot, desired_position=sample.position, desired_er=erd_all,
        position_error=out["err_p"], orientation_error=out["err_o"],
        drift_position=out["drift_p"], drift_orientation=out["drift_o"],
        correction=out["corr"], iterations=iters, manipulability=out["manip"],
        damping=np.zeros(t.size), task=task,
        method="SQP per sample on the self-motion manifold (rest posture, limit band)",
        joint_names=model.joint_names, length_unit=model.length_unit,
        elapsed_s=time.perf_counter() - started, notes=notes)
