"""Random joint values for studies, synthetic data and measurement plans.

Two samplers with distinct meanings: :func:`uniform_joint_values` draws uniformly within
limits (every pose kept), :func:`reachable_poses` also rejects poses whose end effector lies
below a floor height (what a real measuring run can reach).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from zrp.arguments import check_instance, check_int
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import end_effector_pose
from zrp.model.manipulator import Manipulator

__all__ = ["SLIDE_TRAVEL", "default_limits", "reachable_poses", "uniform_joint_values"]


#: A slide without limits moves +- this fraction of the arm's reach in random poses.
SLIDE_TRAVEL = 0.1


def default_limits(model: Manipulator) -> F64:
    """Where random poses lie unless told otherwise, shape (n, 2): +-2.5 rad within the
    model's limits for a revolute joint (+-2.5 rad: within the PUMA 560's ranges for joints 1,
    4, 6 and a little beyond them for 2, 3, 5, which the arm reaches in its own model); the
    model's limits for a prismatic one, or +-:data:`SLIDE_TRAVEL` of the reach when it has none
    (+-2.5 length units would move a slide 5 mm on a 1 m arm, or 5 m on an arm in metres)."""
    check_instance(model, Manipulator, "model", "a zrp.Manipulator")
    pr = np.asarray(model.prismatic, dtype=bool)
    lo = np.where(pr, -SLIDE_TRAVEL * model.reach, np.maximum(-2.5, model.lower))
    hi = np.where(pr, SLIDE_TRAVEL * model.reach, np.minimum(2.5, model.upper))
    fin = pr & np.isfinite(model.lower) & np.isfinite(model.upper)
    return np.column_stack([np.where(fin, model.lower, lo), np.where(fin, model.upper, hi)])


def uniform_joint_values(model: Manipulator, count: int, rng: np.random.Generator,
                 limits_rad: ArrayLike | None = None) -> F64:
    """Uniform random joint values within ``limits_rad`` (shape (n, 2), rad or length unit;
    default :func:`default_limits`), shape (count, n)."""
    check_instance(model, Manipulator, "model", "a zrp.Manipulator")
    check_int(count, "count", 0)
    check_instance(rng, np.random.Generator, "rng", "a numpy.random.Generator")
    lim = (default_limits(model) if limits_rad is None
           else np.asarray(limits_rad, dtype=float))
    if lim.shape != (model.n, 2):
        raise InputError(f"limits_rad: expected shape ({model.n}, 2), got {lim.shape}")
    return rng.uniform(lim[:, 0], lim[:, 1], (count, model.n))


def reachable_poses(model: Manipulator, count: int, rng: np.random.Generator,
                 limits: ArrayLike | None = None, min_height: float | None = None) -> F64:
    """Random reachable poses in measurement order, rad, shape (count, n).

    Uniform within ``limits`` (rad or length unit, shape (n, 2); default
    :func:`default_limits`: +-2.5 rad within the model's own limits, slides within theirs),
    rejecting poses whose end-effector point lies below ``min_height``
    (model length unit, base frame; default: 0.8 reach below the base, where the floor is).
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError(f"count: expected a positive number of poses, got {count!r}")
    n = model.n
    lim = default_limits(model) if limits is None else np.asarray(limits, dtype=float)
    if lim.shape != (n, 2) or not np.all(np.isfinite(lim)) or np.any(lim[:, 0] >= lim[:, 1]):
        raise InputError(f"limits: expected shape ({n}, 2) with lower < upper (rad), got "
                         f"{np.shape(limits)}")
    floor = -0.8 * model.reach if min_height is None else float(min_height)
    out = np.empty((0, n))
    for _ in range(100):
        q = rng.uniform(lim[:, 0], lim[:, 1], (2 * count, n))
        p, _ = end_effector_pose(model, q)
        out = np.vstack([out, q[p[:, 2] >= floor]])
        if len(out) >= count:
            return out[:count]
    raise InputError(f"min_height {floor:g}: fewer than {count} random poses within the limits "
                     "reach above it")
