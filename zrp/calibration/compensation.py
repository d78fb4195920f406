"""Compensation: the joint commands that put the calibrated robot on desired targets.

For target i (a tool point position y*_i, optionally a hand orientation R*_i) the command q_i
solves

    y(q_i) = R_b^T (m(q_i) - t_b) = y*_i   [and  R'_n(x_i) H'_0 = R*_i],   x_i = q_i + dq(q_i)

with the calibrated robot of :mod:`zrp.calibration.calibrated`: the folded geometry and the
joint map (encoder scale, cyclic error, compliance under the gravity torque of the commanded
pose, backlash on the side the joint approaches from in the command sequence). Newton steps
use the geometric Jacobian of the folded model at x (Eq 7: revolute column [u_k; u_k x (y -
p_k)]), pseudo-inverted per target (minimum-norm step from the seed when only a position is
asked of a redundant arm); the joint map's own derivative (<~1e-3) only slows convergence.
Approach directions and gravity torques depend on the commands themselves, so they are
re-evaluated on the solution and the solve repeated until they no longer change.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.calibration.calibrated import CalibratedRobot, PoseConditions, chain
from zrp.calibration.conditions import (
    ConditionWarning,
    MissingConditionError,
    check_joint_limits,
    check_payload,
    missing_conditions,
    out_of_range,
    payload_separated,
)
from zrp.calibration.guards import check_finite, guard, reference_poses
from zrp.calibration.learned import correct_hand
from zrp.errors import InputError, ZRPWarning
from zrp.kinematics.forward import forward_kinematics
from zrp.model.manipulator import hand_frame
from zrp.rotations import er_from_matrix, rotvec_from_er

__all__ = ["Compensation", "ConditionWarning", "ThermalWarning", "compensate",
           "compensate_program", "joint_limits"]

GravityFn = Callable[[F64], F64]


@dataclass(frozen=True, eq=False)
class Compensation:
    """Joint commands for T targets (n joints).

    Attributes:
        target_ids: target labels (T,).
        q_command: the commands, shape (T, n) (rad; prismatic joints in the length unit).
        q_seed: the seed (the uncompensated program where given), shape (T, n).
        predicted: predicted tool-point positions at the commands, base frame, shape (T, 3).
        residual: predicted position error |y - y*| per target (length unit), shape (T,).
        orientation_residual: predicted orientation error (rad), shape (T,), or None.
        uncompensated: predicted position error of the seed commands (T,) (length unit).
        sigma_min: smallest singular value of the Jacobian [u; J_v / L] (L: the model's
            characteristic length) at the command, shape (T,).
        near_singular: sigma_min below the threshold (a share of the arm's own median,
            :mod:`zrp.calibration.guards`), shape (T,).
        near_limit: a joint within the margin of its limit, shape (T,) (False without limits).
        converged: the solve met its tolerance, shape (T,).
        outside_measured: a command outside the joint ranges the calibration measured (or
            the training ranges of its learned residual term), shape (T,) (compensated only
            with ``accept_flagged``).
    """

    target_ids: tuple[str, ...]
    q_command: F64
    q_seed: F64
    predicted: F64
    residual: F64
    orientation_residual: F64 | None
    uncompensated: F64
    sigma_min: F64
    near_singular: NDArray[np.bool_]
    near_limit: NDArray[np.bool_]
    converged: NDArray[np.bool_]
    outside_measured: NDArray[np.bool_]

    def __post_init__(self) -> None:
        T = len(self.target_ids)
        if self.q_command.shape[0] != T or self.residual.shape != (T,):
            raise InputError("Compensation: arrays do not match the number of targets")

    def summary(self) -> dict[str, float | int]:
        """RMS / max predicted residual before and after, counts of flagged targets."""
        return {"targets": len(self.target_ids),
                "rms_before": float(np.sqrt(np.mean(self.uncompensated ** 2))),
                "rms_after": float(np.sqrt(np.mean(self.residual ** 2))),
                "max_after": float(self.residual.max()),
                "not_converged": int((~self.converged).sum()),
                "near_singular": int(self.near_singular.sum()),
                "near_limit": int(self.near_limit.sum()),
                "outside_measured": int(self.outside_measured.sum())}


@dataclass(frozen=True)
class _Targets:
    y: F64                  # (T, 3) base frame
    rot: F64 | None         # (T, 3, 3) hand frames, base frame
    tool: F64               # (3,) t'_j


def _approach(q: F64) -> F64:
    """Approach direction of each joint from the command order (as
    :meth:`zrp.gap.Measurements.approach_direction`): sign of the change from the previous
    command, kept when the joint does not move, 0 before it first moves; shape (T, n)."""
    d = np.zeros_like(q)
    for i in range(1, len(q)):
        s = np.sign(q[i] - q[i - 1])
        d[i] = np.where(s != 0.0, s, d[i - 1])
    return d


def _conditions(cond: PoseConditions, gravity: GravityFn | None, q: F64) -> PoseConditions:
    """The pose conditions at commands q: explicit approach directions (from the order of q
    unless given) and the gravity torques at q (when a function is given)."""
    out = cond if cond.direction is not None else replace(cond, direction=_approach(q))
    return out if gravity is None else replace(out, gravity_torque=gravity(q))


def _subset(cond: PoseConditions, tg: _Targets, idx: NDArray[np.int64]
            ) -> tuple[PoseConditions, _Targets]:
    def pick(a: ArrayLike | None) -> F64 | None:
        return None if a is None else np.asarray(a, dtype=float)[idx]

    return (PoseConditions(pick(cond.direction), pick(cond.gravity_torque), pick(cond.temp),
                           pick(cond.load)),
            _Targets(tg.y[idx], None if tg.rot is None else tg.rot[idx], tg.tool))


def _kinematics(cal: CalibratedRobot, x: F64, tool: F64, scale: F64 | None
                ) -> tuple[F64, F64, F64, F64]:
    """Tool point y (T, 3), hand rotation (T, 3, 3) and the columns of the position and
    rotation Jacobians, J_v and J_w (T, n, 3), at actual joint values x."""
    pos, rn, pts, axes = chain(cal.model, x, scale)
    y = pos + rn @ tool
    prism = cal.model.prismatic[None, :, None]
    jv = np.where(prism, axes, np.cross(axes, y[:, None, :] - pts))      # (T, n, 3)
    return y, rn, jv, np.where(prism, 0.0, axes)


def _errors(cal: CalibratedRobot, q: F64, cond: PoseConditions, tg: _Targets
            ) -> tuple[F64, F64, F64]:
    """Error vector (T, 3 or 6), Jacobian (T, 3 or 6, n) and the 6-row scaled Jacobian."""
    x = cal.actual_joint_values(q, cond)
    y, rn, jv, jw = _kinematics(cal, x, tg.tool, cal.body_scale(len(x), cond.temp))
    y, rn = correct_hand(cal.learned, cal.base_rotation, cal.tool_points, q, y, rn, tg.tool)
    L = cal.model.characteristic_length
    full = np.concatenate([jw, jv / L], axis=2).transpose(0, 2, 1)      # (T, 6, n)
    e = y - tg.y
    J = jv.transpose(0, 2, 1)
    if tg.rot is not None:
        ee = cal.model.end_effector
        r = rn @ hand_frame(ee.axial, ee.transverse)
        er = rotvec_from_er(er_from_matrix(r @ np.swapaxes(tg.rot, 1, 2)))
        e = np.concatenate([e, er * L], axis=1)
        J = np.concatenate([J, jw.transpose(0, 2, 1) * L], axis=1)
    return e, J, full


def _newton(cal: CalibratedRobot, q: F64, cond: PoseConditions, tg: _Targets, tol: float,
            max_iter: int) -> F64:
    """Gauss-Newton with step halving per target (the error norm never grows); only the
    targets not yet converged (and still improving) are evaluated. ``cond`` must carry
    explicit directions (a subset keeps them)."""
    q = q.copy()
    e, _, _ = _errors(cal, q, cond, tg)
    norm = np.linalg.norm(e, axis=1)
    active = np.flatnonzero(norm >= tol)
    for _ in range(max_iter):
        if not active.size:
            break
        c, t = _subset(cond, tg, active)
        qa, na = q[active], norm[active]
        ea, Ja, _ = _errors(cal, qa, c, t)
        step = -np.einsum("tij,tj->ti", np.linalg.pinv(Ja, rcond=1e-7), ea)
        big = np.abs(step).max(axis=1, keepdims=True)
        step *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))   # at most 0.5 rad a step
        for _ in range(8):
            e1, _, _ = _errors(cal, qa + step, c, t)
            n1 = np.linalg.norm(e1, axis=1)
            better = n1 < na
            if better.all():
                break
            step[~better] *= 0.5
        q[active[better]] = qa[better] + step[better]
        norm[active[better]] = n1[better]
        active = active[better & (n1 >= tol)]
    return q


def _check_limits(q: F64, lim: F64, margin: float, ids: tuple[str, ...]
                  ) -> NDArray[np.bool_]:
    out = (q < lim[:, 0]) | (q > lim[:, 1])
    if out.any():
        i, k = map(int, np.argwhere(out)[0])
        raise InputError(f"target {ids[i]}: the compensated command of joint {k + 1} is "
                         f"{q[i, k]:.6g}, beyond its limit [{lim[k, 0]:.6g}, {lim[k, 1]:.6g}] "
                         f"({int(out.any(axis=1).sum())} target(s) out of limits); move the "
                         "target or relax limits")
    return np.any((q < lim[:, 0] + margin) | (q > lim[:, 1] - margin), axis=1)


class ThermalWarning(ZRPWarning):
    """Thermal expansion was identified but the targets' temperature is not known."""


def _checked_targets(cal: CalibratedRobot, targets: ArrayLike, seed: ArrayLike,
                     orientations: ArrayLike | None, frame: str,
                     target_ids: tuple[str, ...] | None
                     ) -> tuple[F64, F64, tuple[str, ...], F64 | None]:
    """(targets in the base frame (T, 3), seeds (T, n), target labels, orientations
    (T, 3, 3) or None), shapes checked."""
    y = np.atleast_2d(np.asarray(targets, dtype=float))
    if y.ndim != 2 or y.shape[1] != 3:
        raise InputError(f"targets: expected shape (T, 3), got {np.shape(targets)}")
    T = len(y)
    q0 = np.broadcast_to(np.asarray(seed, dtype=float), (T, cal.n)).copy()
    ids = tuple(str(i) for i in range(1, T + 1)) if target_ids is None else tuple(target_ids)
    if len(ids) != T:
        raise InputError(f"target_ids: expected {T} labels, got {len(ids)}")
    if frame == "instrument":
        y = (y - np.asarray(cal.base_translation)) @ np.asarray(cal.base_rotation)
    elif frame != "base":
        raise InputError(f"frame: expected 'base' or 'instrument', got {frame!r}")
    rot = None if orientations is None else np.asarray(orientations, dtype=float)
    if rot is not None and rot.shape != (T, 3, 3):
        raise InputError(f"orientations: expected shape ({T}, 3, 3), got {rot.shape}")
    return y, q0, ids, rot


def _warn_conditions(cal: CalibratedRobot, base: PoseConditions) -> None:
    """Refuse a payload the calibration cannot predict (:func:`~zrp.calibration.conditions.
    check_payload`); warn (at the caller of :func:`compensate`) when thermal expansion was
    identified but the targets' temperature is not given, when a payload-dependent joint map
    identified with a payload gets none, and when a temperature or payload lies outside the
    measured range."""
    if cal.kappa != 0.0 and base.temp is None:
        warnings.warn(f"the calibration found thermal expansion (kappa = {cal.kappa:.3g} "
                      f"1/degC) but no temperature was given (conditions=PoseConditions("
                      f"temp=...)): the commands are for the reference temperature "
                      f"{cal.t_ref:.4g} degC", ThermalWarning, stacklevel=3)
    check_payload(cal.conditions, cal.compliance_model, base.load, required=False)
    try:
        missing_conditions(cal.terms, cal.compliance_model, 0.0, cal.conditions,
                           temp=base.temp, load=base.load)
    except MissingConditionError as exc:
        own = not payload_separated(cal.conditions, cal.compliance_model)
        warnings.warn(f"{exc} (conditions=PoseConditions(load=...)); the commands are for "
                      + ("the payload of the data" if own else "no payload"),
                      ConditionWarning, stacklevel=3)
    for msg in out_of_range(cal.conditions, temp=base.temp, load=base.load):
        warnings.warn(msg, ConditionWarning, stacklevel=3)


def joint_limits(cal: CalibratedRobot, limits: ArrayLike | None) -> F64:
    """The limits to enforce, shape (n, 2): ``limits`` when given, else the calibrated
    model's own (+-inf for a joint without)."""
    if limits is None:
        return np.stack([cal.model.lower, cal.model.upper], axis=1)
    lim = np.asarray(limits, dtype=float)
    if lim.shape != (cal.n, 2) or np.any(~(lim[:, 0] < lim[:, 1])):
        raise InputError(f"limits: expected shape ({cal.n}, 2) with lower < upper, got "
                         f"{lim.shape}")
    return lim


def _solve(cal: CalibratedRobot, q0: F64, cond: PoseConditions, base: PoseConditions,
           gravity_torque: GravityFn | None, tg: _Targets, tol: float, max_iter: int,
           max_rounds: int) -> tuple[F64, PoseConditions]:
    """Newton solves from ``q0`` under ``cond`` (the conditions at ``q0``), repeated while
    the approach directions and gravity torques, re-evaluated on the solution, leave an error;
    (commands, their conditions)."""
    q = q0
    adaptive = gravity_torque is not None or base.direction is None
    for _ in range(max_rounds):
        q = _newton(cal, q, cond, tg, tol, max_iter)
        if not adaptive:
            break
        cond = _conditions(base, gravity_torque, q)
        e_new, _, _ = _errors(cal, q, cond, tg)
        if np.all(np.linalg.norm(e_new, axis=1) < tol):
            break
    return q, cond


def compensate(cal: CalibratedRobot, targets: ArrayLike, seed: ArrayLike, *,
               orientations: ArrayLike | None = None, point: str | None = None,
               frame: str = "base", conditions: PoseConditions | None = None,
               gravity_torque: GravityFn | None = None, limits: ArrayLike | None = None,
               limit_margin: float = np.radians(1.0), singular_tol: float | None = None,
               tol: float = 1e-9, max_iter: int = 30, max_rounds: int = 5,
               target_ids: tuple[str, ...] | None = None,
               accept_flagged: bool = False) -> Compensation:
    """Joint commands that put ``point`` of the calibrated robot on ``targets``.

    Args:
        cal: the calibrated robot.
        targets: desired positions of the tool point, shape (T, 3) (length unit, ``frame``).
        seed: starting joint values (e.g. the uncompensated program), shape (T, n) or (n,).
        orientations: desired hand frames (columns n, s, a as :func:`zrp.hand_frame`) in the
            base frame, shape (T, 3, 3), or None (position only).
        point: the tool point (a label of ``cal.tool_labels``), None for the model's end point.
        frame: "base" or "instrument" (the frame of ``targets``).
        conditions: temperatures, loads, explicit approach directions (default: directions
            from the order of the commands, re-evaluated on the solution).
        gravity_torque: for MJCF compliance, a function q (T, n) -> torques (T, n) (N m).
        limits: joint limits, shape (n, 2) (rad / length unit), or None: the calibrated
            model's own (from the model file; none for a joint without). Every seed (the
            program) and every command is checked against them.
        limit_margin: a command closer than this to a limit is flagged.
        singular_tol: an absolute sigma_min threshold for near-singular; None (default):
            a share of the arm's own median conditioning (:mod:`zrp.calibration.guards`).
        accept_flagged: compensate commands outside the measured joint ranges and
            near-singular ones too, flagged per row (default: refused).
        tol: convergence tolerance on the error (length unit; orientation scaled by L).

    Warns:
        ThermalWarning: thermal expansion identified and no temperature given.
        ConditionWarning: a payload-dependent joint map identified with a payload and no
            load given; a temperature or payload outside the measured range.

    Raises:
        InputError: bad shapes, a seed or command beyond a joint limit (naming the target
            and joint), or instrument-frame targets without ``point`` (the instrument measured
            the tool points, not the model's end point: naming the points).
        PayloadConditionError: a payload the calibration cannot predict (identified at one
            payload, never varied, without the MJCF's masses).
        UnmeasuredTargetError: a command outside the measured joint ranges (unless
            ``accept_flagged``).
        NearSingularTargetError: a near-singular command (unless ``accept_flagged``).
    """
    if frame == "instrument" and point is None and cal.tool_labels:
        raise InputError(
            f"point: the targets are in the instrument's frame, where the calibration measured "
            f"the tool points {', '.join(cal.tool_labels)}, not the model's end point; name "
            "the point the targets are for (point=...)")
    y, q0, ids, rot = _checked_targets(cal, targets, seed, orientations, frame, target_ids)
    lim = joint_limits(cal, limits)
    check_joint_limits(q0, lim, ids, "the seed (program) value")
    tg = _Targets(y, rot, cal.tool_offset(point))
    base = conditions or PoseConditions()
    _warn_conditions(cal, base)
    cond = _conditions(base, gravity_torque, q0)
    e0, _, _ = _errors(cal, q0, cond, tg)
    q, cond = _solve(cal, q0, cond, base, gravity_torque, tg, tol, max_iter, max_rounds)
    e, _, full = _errors(cal, q, cond, tg)
    check_finite(ids, q, e, e0, y + e[:, :3], learned=cal.learned)
    ok = np.linalg.norm(e, axis=1) < tol
    near_limit = _check_limits(q, lim, limit_margin, ids)
    smin = np.linalg.svd(full, compute_uv=False)[:, -1]
    outside, near = guard(ids, q, smin, cal.conditions, lambda: _reference_sigma(cal, tg),
                          accept_flagged=accept_flagged, singular_tol=singular_tol,
                          learned=cal.learned)
    L = cal.model.characteristic_length
    return Compensation(ids, q, q0, y + e[:, :3], np.linalg.norm(e[:, :3], axis=1),
                        None if rot is None else np.linalg.norm(e[:, 3:], axis=1) / L,
                        np.linalg.norm(e0[:, :3], axis=1), smin, near, near_limit, ok,
                        outside)


def _reference_sigma(cal: CalibratedRobot, tg: _Targets) -> float:
    """The median sigma_min of the calibrated geometry over the reference poses (eq. G1 of
    :mod:`zrp.calibration.guards`)."""
    _, _, jv, jw = _kinematics(cal, reference_poses(cal.model, cal.conditions), tg.tool, None)
    full = np.concatenate([jw, jv / cal.model.characteristic_length], axis=2)
    return float(np.median(np.linalg.svd(full, compute_uv=False)[:, -1]))


def compensate_program(cal: CalibratedRobot, q_program: ArrayLike, **kwargs: object
                       ) -> Compensation:
    """Compensate a joint program: the targets are the poses of the nominal model at the
    program's joint values (end point and hand frame, base frame), the seed the program.
    Keyword arguments as :func:`compensate` (not ``targets``, ``seed``, ``orientations``,
    ``point``, ``frame``)."""
    qp = np.atleast_2d(np.asarray(q_program, dtype=float))
    if qp.ndim != 2 or qp.shape[1] != cal.n:
        raise InputError(f"q_program: expected shape (T, {cal.n}), got {np.shape(q_program)}")
    fk = forward_kinematics(cal.nominal, qp)
    rot = fk.rotation @ cal.nominal.end_effector.frame
    return compensate(cal, fk.position, qp, orientations=rot, point=None, frame="base",
                      **kwargs)  # type: ignore[arg-type]
