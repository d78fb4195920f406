"""Inverse kinematics along a trajectory by integrating the joint rates of eq (7).

Each step integrates qdot = J^# [omega_d; v_d] (damped least squares near singularities)
with the Adams-Bashforth-Moulton predictor-corrector of order 4, started by classical
Runge-Kutta 4. Drift is corrected in closed loop, either by Newton projection onto the desired
pose after each step (``correction="newton"``, the default: the tracking error is then at the
rounding floor and the correction applied is reported per step), or by a proportional feedback
term in the rates (``"feedback"``), or not at all (``"none"``, the bare integrator, whose
error shows its order of accuracy).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arguments import check_float, check_int
from zrp.arrays import F64
from zrp.errors import (
    IKError,
    InputError,
    JointLimitError,
    SingularityError,
    SingularityWarning,
    TrackingWarning,
    UnreachableError,
)
from zrp.escape import csv_text
from zrp.kinematics import _ik_kernels as IKK
from zrp.kinematics.choices import CORRECTIONS, TASKS
from zrp.kinematics.forward import _karrays, check_q, end_effector_pose
from zrp.kinematics.posture import check_limits_along
from zrp.kinematics.trajectory import Trajectory
from zrp.model.manipulator import Manipulator
from zrp.output import write_text

__all__ = ["CORRECTIONS", "TASKS", "IKResult", "track_trajectory"]



@dataclass(frozen=True, eq=False)
class IKResult:
    """Joint trajectory and per-step diagnostics. N + 1 samples (N steps).

    Attributes:
        t: times, shape (N+1,), s.
        q: joint values, shape (N+1, n) (rad or length unit).
        qdot: joint rates from eq (7), shape (N+1, n).
        desired_position: shape (N+1, 3); desired_er: hand orientation, shape (N+1, 4).
        position_error: |p_d - p(q)| after correction, shape (N+1,), length unit.
        orientation_error: angle of R_d R(q)^T after correction, shape (N+1,), rad (0 for the
            position task).
        drift_position, drift_orientation: the same errors before the correction, i.e. what
            the predictor-corrector alone left, shape (N+1,).
        correction: |delta q| applied by the correction at each step, shape (N+1,).
        iterations: Newton iterations per step, shape (N+1,).
        manipulability: sqrt(det(Js Js^T)) of the dimensionless Jacobian Js (velocity rows
            divided and prismatic columns multiplied by the characteristic length), shape
            (N+1,).
        damping: damped-least-squares factor lambda used, shape (N+1,) (0 away from
            singularities).
    """

    t: F64
    q: F64
    qdot: F64
    desired_position: F64
    desired_er: F64
    position_error: F64
    orientation_error: F64
    drift_position: F64
    drift_orientation: F64
    correction: F64
    iterations: NDArray[np.int64]
    manipulability: F64
    damping: F64
    task: str
    method: str
    joint_names: tuple[str, ...]
    length_unit: str
    elapsed_s: float = 0.0
    notes: tuple[str, ...] = field(default=())
    includes_compilation: bool = False

    @property
    def steps(self) -> int:
        return self.t.size - 1

    def summary(self) -> dict[str, Any]:
        """Key figures as plain Python values (what ``zrp ik`` prints)."""
        i = int(np.argmin(self.manipulability))
        return {
            "steps": self.steps,
            "duration_s": float(self.t[-1]),
            "task": self.task,
            "method": self.method,
            "max_position_error": float(self.position_error.max()),
            "max_orientation_error_rad": float(self.orientation_error.max()),
            "max_drift_position": float(self.drift_position.max()),
            "max_drift_orientation_rad": float(self.drift_orientation.max()),
            "max_correction": float(self.correction.max()),
            "min_manipulability": float(self.manipulability[i]),
            "min_manipulability_t_s": float(self.t[i]),
            "damped_steps": int(np.count_nonzero(self.damping)),
            "length_unit": self.length_unit,
            "elapsed_s": self.elapsed_s,
            "elapsed_includes_compilation": self.includes_compilation,
            "notes": list(self.notes),
        }

    def csv_text(self) -> str:
        """t, q, qdot and the per-step diagnostics as CSV text, one row per sample."""
        names = list(self.joint_names)
        header = (["t_s", *names, *[f"{nm}_dot" for nm in names], "position_error",
                   "orientation_error_rad", "drift_position", "drift_orientation_rad",
                   "correction", "manipulability", "damping"])
        cols = np.column_stack([self.t, self.q, self.qdot, self.position_error,
                                self.orientation_error, self.drift_position,
                                self.drift_orientation, self.correction,
                                self.manipulability, self.damping])
        return csv_text(header, ([repr(float(x)) for x in row] for row in cols))

    def save_csv(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`csv_text` to ``path`` (atomically, through :mod:`zrp.output`).

        Raises:
            OutputExistsError: ``path`` exists and ``overwrite`` is False.
        """
        return write_text(path, self.csv_text(), overwrite=overwrite)


def _reachability(model: Manipulator, t: F64, p: F64) -> None:
    if model.prismatic.any():
        return  # a prismatic joint's travel is unbounded in the model
    base = model.bodies[0]
    reach = float(np.sum(np.linalg.norm(model.bodies[1:], axis=1)))
    dist = np.linalg.norm(p - base, axis=1)
    bad = dist > reach * (1 + 1e-12)
    if bad.any():
        i = int(np.argmax(bad))
        raise UnreachableError(
            f"the trajectory leaves the workspace at t = {t[i]:.6g} s: point "
            f"{np.round(p[i], 6).tolist()} is {dist[i]:.6g} {model.length_unit} from joint 1, "
            f"beyond the arm's reach of {reach:.6g} {model.length_unit}")


def _check_task(model: Manipulator, task: str | None, correction: str, gain: float | None
                ) -> tuple[str, float]:
    """Validated (task, gain): the task defaults by the number of joints, the gain by the
    correction."""
    if task is None:
        task = "pose" if model.n >= 6 else "position"
    if task not in TASKS:
        raise InputError(f"task: {task!r} is unknown; expected one of {TASKS}")
    if correction not in CORRECTIONS:
        raise InputError(f"correction: {correction!r} is unknown; expected one of {CORRECTIONS}")
    if gain is None:
        gain = 50.0 if correction == "feedback" else 0.0
    if not np.isfinite(gain) or gain < 0:
        raise InputError(f"gain: expected a finite number >= 0 (1/s), got {gain!r}")
    return task, gain


def _warn_risky(model: Manipulator, trajectory: Trajectory, steps: int, task: str,
                correction: str, gain: float) -> None:
    """Warns (at the caller of the tracking function) about options that track badly."""
    if correction == "feedback" and gain * trajectory.duration / steps > 0.3:
        warnings.warn(f"gain * h = {gain * trajectory.duration / steps:.3g} exceeds 0.3: the "
                      f"feedback is outside the predictor-corrector's stability region; use "
                      f"more steps or a smaller gain", TrackingWarning, stacklevel=4)
    if task == "pose" and model.n < 6:
        warnings.warn(f"task='pose' with {model.n} joints: the orientation cannot be tracked "
                      "independently; damped least squares will share the error",
                      TrackingWarning, stacklevel=4)


def _check_options(model: Manipulator, trajectory: Trajectory, q0: ArrayLike, steps: int,
                   task: str | None, correction: str, gain: float | None
                   ) -> tuple[F64, int, str, float]:
    """Validated (q0, steps, task, gain); warns (at the caller's caller) about risky options."""
    if not isinstance(trajectory, Trajectory):
        raise InputError(f"trajectory: expected a zrp Trajectory (Circle, Line, "
                         f"FunctionTrajectory), got {type(trajectory).__name__}")
    q0 = np.array(check_q(model, q0, "q0"), dtype=float)
    if q0.shape != (model.n,):
        raise InputError(f"q0: expected shape ({model.n},), got {q0.shape}")
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 4:
        raise InputError(f"steps: expected an integer >= 4, got {steps!r}")
    task, gain = _check_task(model, task, correction, gain)
    _warn_risky(model, trajectory, steps, task, correction, gain)
    return q0, int(steps), task, float(gain)


def _desired_orientation(model: Manipulator, q0: F64, sample: Any, mid: Any,
                         n_steps: int) -> tuple[F64, F64, F64, F64]:
    """(er, omega) at the samples and at the three RK4 midpoints; without an orientation law
    the hand keeps its orientation at ``q0``."""
    if sample.er is not None:
        return sample.er, sample.omega, mid.er, mid.omega
    _, er0 = end_effector_pose(model, q0)
    return (np.tile(er0, (n_steps + 1, 1)), np.zeros((n_steps + 1, 3)), np.tile(er0, (3, 1)),
            np.zeros((3, 3)))


def _check_reached(model: Manipulator, t: F64, sample: Any, out: dict[str, F64],
                   correction: str, manipulability_threshold: float) -> None:
    bad = out["err_p"] > 1e-3 * model.characteristic_length
    if bad.any() and correction != "none":
        i = int(np.argmax(bad))
        pt = np.round(sample.position[i], 6).tolist()
        dist = float(np.linalg.norm(sample.position[i] - model.bodies[0]))
        reach = float(np.sum(np.linalg.norm(model.bodies[1:], axis=1)))
        if out["manip"][i] < manipulability_threshold and dist <= reach:
            raise SingularityError(
                f"cannot follow the path at t = {t[i]:.6g} s: point {pt} is within reach "
                f"({dist:.6g} of {reach:.6g} {model.length_unit}) but the arm is at a "
                f"singularity (manipulability {out['manip'][i]:.3g}); it stays "
                f"{out['err_p'][i]:.4g} {model.length_unit} away")
        raise UnreachableError(
            f"cannot reach the desired pose at t = {t[i]:.6g} s: point {pt} stays "
            f"{out['err_p'][i]:.4g} {model.length_unit} away (manipulability "
            f"{out['manip'][i]:.3g}); the target is outside the workspace")


def _notes(model: Manipulator, t: F64, sample: Any, out: dict[str, F64], use_newton: bool,
           position_tol: float, orientation_tol_rad: float) -> list[tuple[str, type[Warning]]]:
    """Diagnostics worth a warning: damped samples, and samples where Newton missed its
    tolerance."""
    notes: list[tuple[str, type[Warning]]] = []
    length = model.characteristic_length
    damped = np.flatnonzero(out["lam"] > 0)
    if damped.size:
        i = int(damped[np.argmin(out["manip"][damped])])
        notes.append((f"near a singularity on {damped.size} of {t.size} samples (t = "
                      f"{t[damped[0]]:.4g}..{t[damped[-1]]:.4g} s); lowest manipulability "
                      f"{out['manip'][i]:.3g} at t = {t[i]:.4g} s, point "
                      f"{np.round(sample.position[i], 4).tolist()}; damped least squares "
                      "active", SingularityWarning))
    if use_newton:
        loose = (out["err_p"] > max(position_tol, 1e-12 * length) * 100) | (
            out["err_o"] > max(orientation_tol_rad, 1e-14) * 100)
        if loose.any():
            i = int(np.argmax(out["err_p"] / length + out["err_o"]))
            notes.append((f"tracking tolerance missed on {int(loose.sum())} samples; worst at "
                          f"t = {t[i]:.4g} s: position error {out['err_p'][i]:.3g} "
                          f"{model.length_unit}, orientation error {out['err_o'][i]:.3g} rad",
                          TrackingWarning))
    return notes


def _limit_notes(model: Manipulator, t: F64, q: F64, mode: str
                 ) -> list[tuple[str, type[Warning]]]:
    if mode not in ("error", "warn", "ignore"):
        raise InputError(f"limits: {mode!r} is unknown; expected 'error', 'warn' or 'ignore'")
    if mode == "ignore":
        return []
    try:
        check_limits_along(model, t, q)
    except JointLimitError as exc:
        if mode == "error":
            raise
        return [(str(exc), TrackingWarning)]
    return []


def track_trajectory(
    model: Manipulator,
    trajectory: Trajectory,
    q0: ArrayLike,
    steps: int = 1000,
    *,
    task: Literal["pose", "position"] | None = None,
    correction: Literal["newton", "feedback", "none"] = "newton",
    gain: float | None = None,
    position_tol: float | None = None,
    orientation_tol_rad: float = 1e-13,
    max_iter: int = 20,
    manipulability_threshold: float = 1e-3,
    max_damping: float = 0.05,
    warn: bool = True,
    limits: Literal["error", "warn", "ignore"] = "error",
) -> IKResult:
    """Solve the inverse kinematics along ``trajectory`` from the start configuration ``q0``.

    Args:
        model: the manipulator.
        trajectory: desired p(t) (and optionally the hand orientation; default: held at the
            orientation of ``q0``).
        q0: start configuration, shape (n,); it is first corrected onto the trajectory's start
            point by Newton steps (the correction is reported at step 0).
        steps: number of integration steps N (fixed step h = duration / N).
        task: "pose" (position and orientation, 6 rows of eq 7) or "position" (3 rows).
            Default: "pose" for n >= 6, else "position".
        correction: "newton" (project onto the desired pose after each step), "feedback"
            (rates track v_d + gain * error) or "none" (bare predictor-corrector).
        gain: feedback gain in 1/s (default 0 for "newton"/"none", 50 for "feedback").
        position_tol: Newton tolerance in length units (default 1e-14 times the model's
            characteristic length, i.e. the rounding floor).
        orientation_tol_rad: Newton tolerance on the orientation error.
        max_iter: Newton iterations per step at most.
        manipulability_threshold: below this manipulability the least squares are damped.
        max_damping: damping factor lambda reached at zero manipulability.
        warn: emit :class:`SingularityWarning` / :class:`TrackingWarning`.
        limits: when the solved joints leave the model's joint limits: "error" (default,
            :class:`JointLimitError` naming the joint and time), "warn" (a TrackingWarning) or
            "ignore". The rates themselves ignore the limits; :func:`zrp.track_posture` keeps
            redundant arms inside them.

    Raises:
        UnreachableError: a trajectory point lies beyond the arm's reach, or the pose cannot be
            reached within 1e-3 of the characteristic length (time and point in the message).
        IKError: the integration diverged.
        SingularityError: a point within reach that the arm cannot follow at a singularity.
        JointLimitError: with ``limits="error"``, the path needs a joint beyond its limits.
        InputError: an invalid argument, e.g. a tolerance that is not a positive finite number
            (naming it).
    """
    q0, n_steps, task, gain = _check_options(model, trajectory, q0, steps, task, correction,
                                             gain)
    length = model.characteristic_length
    if position_tol is None:
        position_tol = 1e-14 * length
    # a zero, negative or NaN tolerance would iterate to max_iter everywhere (or never stop
    # correcting): refused by name, as every other option
    position_tol = check_float(position_tol, "position_tol", 0.0, open_lo=True,
                               unit=model.length_unit)
    orientation_tol_rad = check_float(orientation_tol_rad, "orientation_tol_rad", 0.0,
                                      open_lo=True, unit="rad")
    max_iter = check_int(max_iter, "max_iter", 1)

    h = trajectory.duration / n_steps
    t = np.linspace(0.0, trajectory.duration, n_steps + 1)
    tm = t[:3] + 0.5 * h
    sample = trajectory.evaluate(t)
    mid = trajectory.evaluate(tm)
    _reachability(model, t, sample.position)

    erd, wd, erm, wm = _desired_orientation(model, q0, sample, mid, n_steps)
    m = 6 if task == "pose" else 3
    out = {k: np.zeros(n_steps + 1) for k in
           ("manip", "lam", "drift_p", "drift_o", "err_p", "err_o", "corr")}
    iters = np.zeros(n_steps + 1, dtype=np.int64)
    q_out = np.zeros((n_steps + 1, model.n))
    qd_out = np.zeros((n_steps + 1, model.n))
    use_newton = correction == "newton"
    first_call = not IKK.integrate.signatures  # compiles (or loads from cache) on this call
    started = time.perf_counter()
    status, k_fail = IKK.integrate(
        q0, h, np.ascontiguousarray(sample.position), np.ascontiguousarray(sample.velocity),
        np.ascontiguousarray(erd), np.ascontiguousarray(wd),
        np.ascontiguousarray(mid.position), np.ascontiguousarray(mid.velocity),
        np.ascontiguousarray(erm), np.ascontiguousarray(wm), *_karrays(model), m,
        1.0 / length, np.where(model.prismatic, length, 1.0), gain,
        float(manipulability_threshold), float(max_damping),
        use_newton, float(position_tol), float(orientation_tol_rad), int(max_iter),
        q_out, qd_out, out["manip"], out["lam"], out["drift_p"], out["drift_o"], out["err_p"],
        out["err_o"], out["corr"], iters)
    elapsed = time.perf_counter() - started
    if status != IKK.STATUS_OK:
        raise IKError(f"the integration diverged at t = {t[k_fail]:.6g} s (point "
                      f"{np.round(sample.position[k_fail], 6).tolist()}): joint values became "
                      f"non-finite; try more steps or a start configuration away from "
                      f"singularities")
    _check_reached(model, t, sample, out, correction, manipulability_threshold)
    notes = _notes(model, t, sample, out, use_newton, position_tol, orientation_tol_rad)
    notes += _limit_notes(model, t, q_out, limits)
    if warn:
        for msg, category in notes:
            warnings.warn(msg, category, stacklevel=2)
    return IKResult(
        t=t, q=q_out, qdot=qd_out, desired_position=sample.position, desired_er=erd,
        position_error=out["err_p"], orientation_error=out["err_o"],
        drift_position=out["drift_p"], drift_orientation=out["drift_o"],
        correction=out["corr"], iterations=iters, manipulability=out["manip"],
        damping=out["lam"], task=task, method=f"ABM4-PECE (RK4 start), correction={correction}",
        joint_names=model.joint_names, length_unit=model.length_unit, elapsed_s=elapsed,
        notes=tuple(msg for msg, _ in notes), includes_compilation=first_call)
