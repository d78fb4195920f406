"""Guarded compensation: targets whose commands leave what the calibration measured.

A calibrated robot is known where its data were taken. :func:`guard` refuses, by default,

* a command **outside the measured joint ranges** (the data's smallest and largest value of
  each joint, :attr:`~zrp.calibration.conditions.Conditions.joint_ranges`, by more than
  :data:`RANGE_SHARE` of the range): the joint map and the geometry there are extrapolated;
* a **near-singular** command: the smallest singular value sigma_min of the scaled Jacobian
  [u; J_v / L] (:class:`~zrp.calibration.Compensation`) below :data:`NEAR_SINGULAR_SHARE`
  of the arm's own typical conditioning (eq. G1), where a small position correction needs a
  large joint motion (and the model's errors are amplified as much).

Eq. G1, the reference: the median sigma_min of the calibrated geometry over
:data:`REFERENCE_POSES` joint vectors drawn uniformly (seeded: the same every time) within the
measured joint ranges (the model's limits, else +-pi, for a joint without a recorded range)::

    near singular:  sigma_min(command) < NEAR_SINGULAR_SHARE * median_k sigma_min(q_k)

* a command **outside the training ranges of the learned residual term** (when the
  calibration carries one, :mod:`zrp.calibration.learned`; by the same share of its ranges):
  the learned term is extrapolated there.

With ``accept_flagged`` every target is compensated and these rows are flagged in the result
(``outside_measured``, ``near_singular``) and in the commands CSV.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.calibration.conditions import Conditions
from zrp.calibration.learned import LearnedTerm, learned_outside
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator

__all__ = ["NEAR_SINGULAR_SHARE", "RANGE_SHARE", "REFERENCE_POSES", "NearSingularTargetError",
           "NonFiniteResultError", "UnmeasuredTargetError", "check_finite", "guard",
           "reference_poses"]

#: a command whose sigma_min is below this share of the arm's median is near-singular (a
#: correction there costs ten times the joint motion it costs typically, or more).
NEAR_SINGULAR_SHARE = 0.1
#: a command counts as outside a measured range beyond this share of the range's width (a
#: program measured at its own poses moves by its small corrections only).
RANGE_SHARE = 0.02
#: joint vectors of the reference conditioning (eq. G1).
REFERENCE_POSES = 256
#: the accept option's name in messages (the command line's; the API's is accept_flagged).
ACCEPT = "--accept-flagged (API: accept_flagged=True)"


class UnmeasuredTargetError(InputError):
    """A command outside the joint ranges the calibration measured."""


class NearSingularTargetError(InputError):
    """A command near a singularity of the arm (relative to its own conditioning)."""


class NonFiniteResultError(InputError):
    """The calibration predicts a non-finite position or command (NaN, infinity)."""


def check_finite(ids: tuple[str, ...], *arrays: F64, learned: LearnedTerm | None) -> None:
    """Refuse non-finite commands, predictions or errors (each array's first axis: the
    targets; also their squares, which an RMS takes: 1e300 is refused as the inf its square
    is), naming the first target and the field that made them: no command file holds NaN.

    Raises:
        NonFiniteResultError: naming the target and ``learned_residual`` (coef, mean) when the
            calibration carries a learned term, else its values.
    """
    bad = np.zeros(len(ids), dtype=bool)
    with np.errstate(over="ignore", invalid="ignore"):
        for a in arrays:
            rows = np.asarray(a, dtype=float).reshape(len(ids), -1)
            bad |= ~np.isfinite(np.sum(rows ** 2, axis=1))
    if bad.any():
        i = int(np.argmax(bad))
        field = ("learned_residual (its coef and mean: the learned term's correction)"
                 if learned is not None else "its values (joint map, geometry)")
        raise NonFiniteResultError(
            f"target {ids[i]}: the calibration predicts a non-finite position or command "
            f"({int(bad.sum())} target(s)); the field that gives it: {field}. Refused: no "
            "command is written; calibrate again")


def _ranges(model: Manipulator, conditions: Conditions | None) -> F64:
    """(n, 2): the measured range per joint, else the model's limit, else +-pi (revolute)
    or +-the characteristic length (prismatic)."""
    out = np.empty((model.n, 2))
    measured = None if conditions is None else conditions.joint_ranges
    for k, j in enumerate(model.joints):
        r = None if measured is None else measured[k]
        if r is None:
            r = j.limits
        if r is None or not all(math.isfinite(v) for v in r):
            span = model.characteristic_length if model.prismatic[k] else math.pi
            r = (-span, span)
        out[k] = r
    return out


def reference_poses(model: Manipulator, conditions: Conditions | None) -> F64:
    """The joint vectors of eq. G1, shape (:data:`REFERENCE_POSES`, n) (seeded)."""
    r = _ranges(model, conditions)
    rng = np.random.default_rng(0)
    return r[:, 0] + (r[:, 1] - r[:, 0]) * rng.random((REFERENCE_POSES, model.n))


def _outside(q: F64, conditions: Conditions | None) -> NDArray[np.bool_]:
    """(T, n): joint values outside the measured range by more than :data:`RANGE_SHARE` of
    its width (False without a recorded range)."""
    out = np.zeros(q.shape, dtype=bool)
    ranges = None if conditions is None else conditions.joint_ranges
    if ranges is None:
        return out
    for k, r in enumerate(ranges):
        if r is not None:
            tol = RANGE_SHARE * (r[1] - r[0])
            out[:, k] = (q[:, k] < r[0] - tol) | (q[:, k] > r[1] + tol)
    return out


def outside_measured(q: F64, conditions: Conditions | None) -> NDArray[np.bool_]:
    """Per joint value of ``q`` (T, n): outside the range the calibration measured by more
    than :data:`RANGE_SHARE` of its width (False without a recorded range)."""
    return _outside(q, conditions)


def guard(ids: tuple[str, ...], q: F64, sigma_min: F64, conditions: Conditions | None,
          reference: Callable[[], float], *, accept_flagged: bool,
          singular_tol: float | None = None, learned: LearnedTerm | None = None
          ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """(outside the measured ranges or the learned term's training ranges, near-singular)
    per target, shape (T,) each.

    Args:
        ids: target labels; q: the commands (T, n); sigma_min: their sigma_min (T,).
        reference: the median sigma_min of eq. G1 (called only without ``singular_tol``).
        accept_flagged: compensate and flag instead of refusing.
        singular_tol: an absolute sigma_min threshold instead of eq. G1.
        learned: the calibration's learned residual term, or None.

    Raises:
        UnmeasuredTargetError: a command outside a measured range or the learned term's
            training range (naming the target, the joint, its value and the range), unless
            ``accept_flagged``.
        NearSingularTargetError: a near-singular command, unless ``accept_flagged``.
    """
    out = _outside(q, conditions)
    tol = singular_tol if singular_tol is not None else NEAR_SINGULAR_SHARE * reference()
    near = sigma_min < tol
    if not accept_flagged and out.any():
        i, k = map(int, np.argwhere(out)[0])
        lo, hi = conditions.joint_ranges[k]  # type: ignore[union-attr,index]
        raise UnmeasuredTargetError(
            f"target {ids[i]}: the command of joint {k + 1} is {q[i, k]:.6g}, outside the "
            f"range the calibration measured [{lo:.6g}, {hi:.6g}] "
            f"({int(out.any(axis=1).sum())} target(s) outside): the model is extrapolated "
            f"there; measure poses there, or pass {ACCEPT} to compensate them flagged")
    out_learned = (np.zeros(q.shape[0], dtype=bool) if learned is None
                   else _refuse_learned(ids, q, learned, accept_flagged))
    if not accept_flagged and near.any():
        i = int(np.argmax(near))
        why = ("the given singular_tol" if singular_tol is not None else
               f"{NEAR_SINGULAR_SHARE:g} of the arm's median {tol / NEAR_SINGULAR_SHARE:.3g}")
        raise NearSingularTargetError(
            f"target {ids[i]}: the command is near a singularity (sigma_min "
            f"{sigma_min[i]:.3g} < {tol:.3g}, {why}; {int(near.sum())} target(s)): a small "
            f"correction needs a large joint motion there; move the target, or pass {ACCEPT} "
            "to compensate them flagged")
    return out.any(axis=1) | out_learned, near


def _refuse_learned(ids: tuple[str, ...], q: F64, learned: LearnedTerm,
                    accept_flagged: bool) -> NDArray[np.bool_]:
    """Per target, outside the learned term's training ranges (refused unless accepted)."""
    out = learned_outside(learned, q, RANGE_SHARE)
    if not accept_flagged and out.any():
        i, j = map(int, np.argwhere(out)[0])
        k = learned.joints[j]
        lo, hi = learned.training_ranges[j]
        raise UnmeasuredTargetError(
            f"target {ids[i]}: the command of joint {k + 1} is {q[i, k]:.6g}, outside the "
            f"range the learned residual term was trained on [{lo:.6g}, {hi:.6g}] "
            f"({int(out.any(axis=1).sum())} target(s) outside): the learned term is "
            f"extrapolated there; measure poses there, or pass {ACCEPT} to compensate them "
            "flagged")
    return out.any(axis=1)
