"""Euler-Rodrigues parameters (unit quaternions, scalar first), batched over leading axes.

The paper writes a rotation by angle theta about the unit axis u as the four Euler-Rodrigues
parameters (eq 6)::

    e0 = cos(theta/2),  (e1, e2, e3) = u sin(theta/2)

stored here as arrays of shape (..., 4) in the order (e0, e1, e2, e3). Note that scipy's
``Rotation.as_quat`` is scalar-last; use :func:`scipy_quat_from_er` / :func:`er_from_scipy_quat`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64

__all__ = [
    "er_angle",
    "er_conjugate",
    "er_delta_r",
    "er_from_axis_angle",
    "er_from_matrix",
    "er_from_rotvec",
    "er_from_scipy_quat",
    "er_identity",
    "er_multiply",
    "er_rotate",
    "matrix_from_er",
    "rotvec_from_er",
    "scipy_quat_from_er",
]



def er_identity(shape: tuple[int, ...] = ()) -> F64:
    """Identity rotation, shape ``shape + (4,)``."""
    e = np.zeros((*shape, 4))
    e[..., 0] = 1.0
    return e


def er_from_axis_angle(axis: ArrayLike, angle_rad: ArrayLike) -> F64:
    """Eq (6): parameters of the rotation by ``angle_rad`` about the unit ``axis``.

    Args:
        axis: unit vectors, shape (..., 3).
        angle_rad: angles in rad, shape (...) broadcastable against ``axis[..., 0]``.

    Returns:
        shape (..., 4).
    """
    axis = np.asarray(axis, dtype=float)
    half = 0.5 * np.asarray(angle_rad, dtype=float)
    s = np.sin(half)[..., None]
    c = np.cos(half)
    shape = np.broadcast_shapes(axis.shape[:-1], np.shape(c))
    out = np.empty((*shape, 4))
    out[..., 0] = c
    out[..., 1:] = axis * s
    return out


def er_multiply(a: ArrayLike, b: ArrayLike) -> F64:
    """Composition of eqs (4)-(5): the parameters of R(a) R(b) (first b, then a).

    With E = a and e = b, eq (4) is ``E0 e0 - E.e`` and eq (5) is ``E0 e + e0 E + E x e``.

    Args:
        a, b: shape (..., 4), broadcast against each other.

    Returns:
        shape (..., 4).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    a0, av = a[..., :1], a[..., 1:]
    b0, bv = b[..., :1], b[..., 1:]
    w = a0 * b0 - np.sum(av * bv, axis=-1, keepdims=True)
    v = a0 * bv + b0 * av + np.cross(av, bv)
    return np.concatenate([w, v], axis=-1)


def er_conjugate(e: ArrayLike) -> F64:
    """Inverse rotation of unit parameters, shape (..., 4)."""
    e = np.array(e, dtype=float)
    e[..., 1:] *= -1.0
    return e


def er_rotate(e: ArrayLike, v: ArrayLike) -> F64:
    """Eq (2): rotate vectors ``v`` (shape (..., 3)) by parameters ``e`` (shape (..., 4)).

    ``v' = (2 e0^2 - 1) v + 2 (e . v) e + 2 e0 (e x v)``
    """
    e = np.asarray(e, dtype=float)
    v = np.asarray(v, dtype=float)
    e0 = e[..., :1]
    ev = e[..., 1:]
    return (
        (2.0 * e0 * e0 - 1.0) * v
        + 2.0 * np.sum(ev * v, axis=-1, keepdims=True) * ev
        + 2.0 * e0 * np.cross(ev, v)
    )


def matrix_from_er(e: ArrayLike) -> F64:
    """Rotation matrices of unit parameters: shape (..., 4) -> (..., 3, 3)."""
    e = np.asarray(e, dtype=float)
    w, x, y, z = e[..., 0], e[..., 1], e[..., 2], e[..., 3]
    out = np.empty((*e.shape[:-1], 3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def er_from_matrix(r: ArrayLike) -> F64:
    """Parameters (with e0 >= 0) of rotation matrices, shape (..., 3, 3) -> (..., 4).

    Uses Shepperd's method: the largest of the four candidate denominators is used, so the
    result is accurate for every rotation, including half turns.
    """
    r = np.asarray(r, dtype=float)
    tr = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]
    cand = np.stack([tr, r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]], axis=-1)
    i = np.argmax(cand, axis=-1)
    out = np.empty((*r.shape[:-2], 4))
    # Case 0: e0 is largest.
    s0 = np.sqrt(np.maximum(1.0 + tr, 0.0)) * 2.0
    s1 = np.sqrt(np.maximum(1.0 + r[..., 0, 0] - r[..., 1, 1] - r[..., 2, 2], 0.0)) * 2.0
    s2 = np.sqrt(np.maximum(1.0 + r[..., 1, 1] - r[..., 0, 0] - r[..., 2, 2], 0.0)) * 2.0
    s3 = np.sqrt(np.maximum(1.0 + r[..., 2, 2] - r[..., 0, 0] - r[..., 1, 1], 0.0)) * 2.0
    with np.errstate(divide="ignore", invalid="ignore"):
        c0 = np.stack(
            [0.25 * s0, (r[..., 2, 1] - r[..., 1, 2]) / s0, (r[..., 0, 2] - r[..., 2, 0]) / s0,
             (r[..., 1, 0] - r[..., 0, 1]) / s0], axis=-1)
        c1 = np.stack(
            [(r[..., 2, 1] - r[..., 1, 2]) / s1, 0.25 * s1, (r[..., 0, 1] + r[..., 1, 0]) / s1,
             (r[..., 0, 2] + r[..., 2, 0]) / s1], axis=-1)
        c2 = np.stack(
            [(r[..., 0, 2] - r[..., 2, 0]) / s2, (r[..., 0, 1] + r[..., 1, 0]) / s2, 0.25 * s2,
             (r[..., 1, 2] + r[..., 2, 1]) / s2], axis=-1)
        c3 = np.stack(
            [(r[..., 1, 0] - r[..., 0, 1]) / s3, (r[..., 0, 2] + r[..., 2, 0]) / s3,
             (r[..., 1, 2] + r[..., 2, 1]) / s3, 0.25 * s3], axis=-1)
    out = np.select([i[..., None] == k for k in range(4)], [c0, c1, c2, c3])
    out = out / np.linalg.norm(out, axis=-1, keepdims=True)
    return np.where(out[..., :1] < 0.0, -out, out)


def er_angle(e: ArrayLike) -> F64:
    """Rotation angle in rad, in [0, pi], of parameters of shape (..., 4) -> (...)."""
    e = np.asarray(e, dtype=float)
    return 2.0 * np.arctan2(np.linalg.norm(e[..., 1:], axis=-1), np.abs(e[..., 0]))


def rotvec_from_er(e: ArrayLike) -> F64:
    """Rotation vector (axis times angle, rad), shape (..., 4) -> (..., 3)."""
    e = np.asarray(e, dtype=float)
    e = np.where(e[..., :1] < 0.0, -e, e)
    s = np.linalg.norm(e[..., 1:], axis=-1)
    ang = 2.0 * np.arctan2(s, e[..., 0])
    # angle / sin(angle/2) -> 2 as angle -> 0
    with np.errstate(divide="ignore", invalid="ignore"):
        safe = np.where(s > 1e-12, s, 1.0)
        k = np.where(s > 1e-12, ang / safe, 2.0 / np.maximum(e[..., 0], 1e-300))
    return e[..., 1:] * k[..., None]


def er_from_rotvec(rv: ArrayLike) -> F64:
    """Parameters of rotation vectors (rad), shape (..., 3) -> (..., 4)."""
    rv = np.asarray(rv, dtype=float)
    ang = np.linalg.norm(rv, axis=-1)
    half = 0.5 * ang
    # sin(half)/ang -> 1/2 as ang -> 0 (series to second order)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(ang > 1e-8, np.sin(half) / np.where(ang > 1e-8, ang, 1.0), 0.5 - ang**2 / 48.0)
    out = np.empty((*rv.shape[:-1], 4))
    out[..., 0] = np.cos(half)
    out[..., 1:] = rv * k[..., None]
    return out


def er_delta_r(e_err: ArrayLike) -> F64:
    """The paper's rotational deviation, eqs (15)-(16), of an error rotation.

    ``delta_R = sqrt(4 (1 - e0^2 + e.e))`` with ``e0^2 = cos^2(theta/2)`` and
    ``e.e = sin^2(theta/2)``, i.e. ``2 sqrt(2) sin(theta/2)`` (about ``sqrt(2) theta`` for small
    theta). Reported as the paper defines it; see :func:`er_angle` for the plain angle theta.

    Args:
        e_err: unit parameters of the error rotation, shape (..., 4).

    Returns:
        shape (...), dimensionless (numerically close to sqrt(2) times theta in rad).
    """
    e = np.asarray(e_err, dtype=float)
    ee = np.sum(e[..., 1:] ** 2, axis=-1)
    # For unit parameters 1 - e0^2 equals e.e exactly; using e.e avoids the cancellation of
    # 1 - e0^2 near e0 = 1, which would lose all digits for theta below about 1e-8 rad.
    return np.sqrt(8.0 * ee)


def scipy_quat_from_er(e: ArrayLike) -> F64:
    """Scalar-first (e0, e1, e2, e3) -> scipy's scalar-last (x, y, z, w)."""
    e = np.asarray(e, dtype=float)
    return np.concatenate([e[..., 1:], e[..., :1]], axis=-1)


def er_from_scipy_quat(q: ArrayLike) -> F64:
    """scipy's scalar-last (x, y, z, w) -> scalar-first (e0, e1, e2, e3)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)
