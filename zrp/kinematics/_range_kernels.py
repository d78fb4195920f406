"""The range of joint values the kinematics accepts, and its one-pass check (compiled).

Revolute angles are limited to :data:`MAX_ANGLE` rad: the kernels' sine and cosine reduce the
half angle with a three-part Cody-Waite constant, exact (within 1 ulp) up to about 2e6 rad
and off by 1e-9 beyond 1e7 rad; NumPy's would stay exact, but no robot turns 160,000 times.
Prismatic values are limited to :data:`zrp.model.manipulator.MAX_LENGTH` (model length unit),
the bound of every model vector.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from zrp.arrays import F64
from zrp.model.manipulator import MAX_LENGTH, Manipulator, derived

__all__ = ["MAX_ANGLE", "all_in_range", "joint_limits"]

#: Largest |q| of a revolute joint, rad (about 160,000 turns).
MAX_ANGLE = 1e6


def joint_limits(model: Manipulator) -> F64:
    """Per joint the largest accepted |q|: :data:`MAX_ANGLE` rad or ``MAX_LENGTH``, shape (n,)."""
    return derived(model, "_joint_limits", _joint_limits)


def _joint_limits(model: Manipulator) -> F64:
    return np.where(np.asarray(model.prismatic), MAX_LENGTH, MAX_ANGLE)


@njit(cache=True)
def all_in_range(x, lim):
    """True when every element of the contiguous array ``x`` (shape (..., n)) is finite and
    |x[..., k]| <= lim[k] (stops at the first that is not; NaN fails the comparison)."""
    flat = x.ravel()
    n = lim.size
    for i in range(flat.size):
        if not abs(flat[i]) <= lim[i % n]:
            return False
    return True
