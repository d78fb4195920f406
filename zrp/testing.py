"""Helpers for tests and benchmarks: random serial arms, a 7-axis reference arm, and
assertions on poses and models (:func:`assert_pose_close`, :func:`assert_manipulator_close`)
whose message names the first element that differs."""

from __future__ import annotations

from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.model.dh import from_mdh
from zrp.model.manipulator import Manipulator
from zrp.rotations.matrices import rotation_angle
from zrp.rotations.rodrigues import er_angle, er_conjugate, er_multiply, matrix_from_er
from zrp.units import canonical_length_unit

__all__ = [
    "PANDA_LIMITS",
    "assert_manipulator_close",
    "assert_pose_close",
    "panda_mdh",
    "random_arm",
]

#: The Franka Panda's published joint limits, rad, shape (7, 2).
PANDA_LIMITS = ((-2.8973, 2.8973), (-1.7628, 1.7628), (-2.8973, 2.8973), (-3.0718, -0.0698),
                (-2.8973, 2.8973), (-0.0175, 3.7525), (-2.8973, 2.8973))


def panda_mdh() -> Manipulator:
    """The Franka Panda from its published modified-DH table (mm; tool: flange + hand), with
    :data:`PANDA_LIMITS`: a 7-axis arm that needs no robot-description package."""
    rows = [(0, 0, 333, 0), (0, -np.pi / 2, 0, 0), (0, np.pi / 2, 316, 0),
            (82.5, np.pi / 2, 0, 0), (-82.5, -np.pi / 2, 384, 0), (0, np.pi / 2, 0, 0),
            (88, np.pi / 2, 0, 0)]
    tool = np.eye(4)
    tool[2, 3] = 107 + 103.4
    m = from_mdh(rows, tool=tool)
    return Manipulator.from_arrays(
        m.axes, m.bodies, axial=m.end_effector.axial, transverse=m.end_effector.transverse,
        limits=PANDA_LIMITS)


def random_arm(rng: np.random.Generator, n: int, p_prismatic: float = 0.0,
               scale: float = 300.0) -> Manipulator:
    """A random ``n``-joint arm: random unit axes and body vectors of about ``scale`` length
    units (normal components), each joint prismatic with probability ``p_prismatic``."""
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    bodies = rng.normal(size=(n + 1, 3)) * scale
    ua = rng.normal(size=3)
    ua /= np.linalg.norm(ua)
    ut = np.cross(ua, rng.normal(size=3))
    ut /= np.linalg.norm(ut)
    types = ["prismatic" if rng.random() < p_prismatic else "revolute" for _ in range(n)]
    return Manipulator.from_arrays(axes, bodies, axial=ua, transverse=ut, types=types,
                                   name=f"random {n}-joint arm")


# ---- assertions ------------------------------------------------------------------------------
def _pose_parts(pose: Any, name: str) -> tuple[F64, F64]:
    """(positions (..., 3), rotations (..., 4) Euler-Rodrigues or (..., 3, 3) matrices) of a
    pose: a forward-kinematics result (``.position``, ``.er``), a pair (position, rotation) as
    :func:`zrp.end_effector_pose` returns, or homogeneous transforms (..., 4, 4)."""
    if hasattr(pose, "position") and hasattr(pose, "er"):
        return np.asarray(pose.position, dtype=float), np.asarray(pose.er, dtype=float)
    if isinstance(pose, tuple | list) and len(pose) == 2:
        p, r = (np.asarray(x, dtype=float) for x in pose)
        if p.shape[-1:] == (3,) and r.shape in ((*p.shape[:-1], 4), (*p.shape[:-1], 3, 3)):
            return p, r
        raise AssertionError(f"{name}: expected (position (..., 3), rotation (..., 4) or "
                             f"(..., 3, 3)), got shapes {p.shape} and {r.shape}")
    arr = np.asarray(pose)
    if arr.dtype.kind in "iuf" and arr.shape[-2:] == (4, 4):
        arr = arr.astype(float)
        return arr[..., :3, 3], arr[..., :3, :3]
    raise AssertionError(f"{name}: expected a forward-kinematics result, a pair (position, "
                         f"rotation) or (..., 4, 4) transforms, got {type(pose).__name__}")


def _rotation_error(ra: F64, rd: F64) -> F64:
    """Angle (rad) of the rotation from ``rd`` to ``ra``: Euler-Rodrigues parameters composed
    when both are, else the matrices' relative rotation (accurate near zero either way)."""
    if ra.shape[-1] == 4 and rd.shape[-1] == 4:
        return er_angle(er_multiply(ra, er_conjugate(rd)))
    ma = matrix_from_er(ra) if ra.shape[-1] == 4 else ra
    md = matrix_from_er(rd) if rd.shape[-1] == 4 else rd
    return rotation_angle(md, ma)


def _where(index: tuple[int, ...]) -> str:
    return f"pose {index[0] if len(index) == 1 else index}" if index else "the pose"


def assert_pose_close(actual: Any, desired: Any, *, atol_position: float = 1e-9,
                      atol_rotation_rad: float = 1e-12, err_msg: str = "") -> None:
    """Assert that two poses, or batches of poses, agree in position and orientation.

    Args:
        actual, desired: each a forward-kinematics result (:class:`zrp.kinematics.FKResult`:
            ``.position`` and Euler-Rodrigues ``.er``), a pair (position (..., 3), rotation
            as Euler-Rodrigues parameters (..., 4) or matrices (..., 3, 3)), as
            :func:`zrp.end_effector_pose` returns, or homogeneous transforms (..., 4, 4).
            The two may use different rotation forms; their batch shapes must be equal.
        atol_position: largest accepted distance |p_actual - p_desired| (length unit).
        atol_rotation_rad: largest accepted angle of the rotation between them (rad); the
            sign of Euler-Rodrigues parameters does not count (e and -e are one rotation).
        err_msg: prefixed to the failure message.

    Raises:
        AssertionError: naming the first pose (in C order) whose position or rotation is off,
            with both values and the tolerance.
    """
    pa, ra = _pose_parts(actual, "actual")
    pd, rd = _pose_parts(desired, "desired")
    prefix = f"{err_msg}: " if err_msg else ""
    if pa.shape != pd.shape:
        raise AssertionError(f"{prefix}batch shapes differ: actual positions {pa.shape}, "
                             f"desired {pd.shape}")
    dp = np.linalg.norm(pa - pd, axis=-1)
    da = _rotation_error(ra, rd)
    bad = ~(dp <= atol_position) | ~(da <= atol_rotation_rad)   # NaN counts as a difference
    if not np.any(bad):
        return
    index = tuple(int(i) for i in np.argwhere(np.atleast_1d(bad))[0])[:bad.ndim]
    if not (dp[index] <= atol_position):
        raise AssertionError(
            f"{prefix}{_where(index)}: position differs by {dp[index]:.6g} > atol_position "
            f"{atol_position:g} (actual {pa[index].tolist()}, desired {pd[index].tolist()})")
    raise AssertionError(
        f"{prefix}{_where(index)}: rotation differs by {da[index]:.6g} rad > "
        f"atol_rotation_rad {atol_rotation_rad:g} (actual {ra[index].tolist()}, desired "
        f"{rd[index].tolist()})")


def _vector_mismatch(label: str, a: Any, b: Any, atol: float) -> str | None:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    diff = np.max(np.abs(a - b)) if a.shape == b.shape else np.inf
    if diff <= atol or (a.shape == b.shape and np.array_equal(a, b)):  # equal infinities
        return None
    return (f"{label}: {a.tolist()} != {b.tolist()} (largest difference {diff:.6g} > atol "
            f"{atol:g})")


def _limits_mismatch(label: str, a: Any, b: Any, atol: float) -> str | None:
    if a is None or b is None:
        return None if a is b else f"{label}: {a} != {b}"
    return _vector_mismatch(label, a, b, atol)


def _joint_mismatch(k: int, ja: Any, jb: Any, atol: float, atol_length: float) -> str | None:
    if ja.type != jb.type:
        return f"joint {k} type: {ja.type!r} != {jb.type!r}"
    length = atol_length if ja.type == "prismatic" else atol
    return (_vector_mismatch(f"joint {k} axis", ja.axis, jb.axis, atol)
            or _vector_mismatch(f"joint {k} body", ja.body, jb.body, atol_length)
            or _limits_mismatch(f"joint {k} limits", ja.limits, jb.limits, length)
            or _limits_mismatch(f"joint {k} velocity_limit", ja.velocity_limit,
                                jb.velocity_limit, length))


def assert_manipulator_close(a: Manipulator, b: Manipulator, *, atol: float = 1e-12,
                             atol_length: float | None = None, err_msg: str = "") -> None:
    """Assert that two models describe the same arm: length unit, number of joints, then per
    joint (base to tip) its type, axis, body vector, limits and velocity limit, then the end
    effector's body vector, axial and transverse vectors. Names are free text and not compared.

    Args:
        atol: largest accepted difference of a unit-vector component, and of a revolute
            joint's limit (rad).
        atol_length: the same for body-vector components and a prismatic joint's limits (the
            model's length unit); None: ``atol``.
        err_msg: prefixed to the failure message.

    Raises:
        AssertionError: naming the first element that differs, with both values.
    """
    atol_length = atol if atol_length is None else atol_length
    prefix = f"{err_msg}: " if err_msg else ""
    for x, name in ((a, "a"), (b, "b")):
        if not isinstance(x, Manipulator):
            raise AssertionError(f"{prefix}{name}: expected a zrp.Manipulator, got "
                                 f"{type(x).__name__}")
    problem = _model_mismatch(a, b, atol, atol_length)
    if problem:
        raise AssertionError(prefix + problem)


def _model_mismatch(a: Manipulator, b: Manipulator, atol: float,
                    atol_length: float) -> str | None:
    """The first difference of :func:`assert_manipulator_close`'s list, or None."""
    if canonical_length_unit(a.length_unit) != canonical_length_unit(b.length_unit):
        return f"length_unit: {a.length_unit!r} != {b.length_unit!r}"
    if a.n != b.n:
        return f"number of joints: {a.n} != {b.n}"
    for k, (ja, jb) in enumerate(zip(a.joints, b.joints, strict=True), start=1):
        problem = _joint_mismatch(k, ja, jb, atol, atol_length)
        if problem:
            return problem
    ea, eb = a.end_effector, b.end_effector
    return (_vector_mismatch("end_effector body", ea.body, eb.body, atol_length)
            or _vector_mismatch("end_effector axial", ea.axial, eb.axial, atol)
            or _vector_mismatch("end_effector transverse", ea.transverse, eb.transverse, atol))
