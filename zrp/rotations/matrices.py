"""Rotation matrices: cross-product matrices, the SO(3) exponential and its left Jacobian, and
the angle between two frames. Shapes are given per function; angles are in rad.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64

__all__ = ["left_jacobian", "matrix_from_rotvec", "rotation_angle", "skew"]



def skew(v: ArrayLike) -> F64:
    """Cross-product matrices, shape (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    k = np.zeros((*v.shape[:-1], 3, 3))
    k[..., 0, 1], k[..., 0, 2] = -v[..., 2], v[..., 1]
    k[..., 1, 0], k[..., 1, 2] = v[..., 2], -v[..., 0]
    k[..., 2, 0], k[..., 2, 1] = -v[..., 1], v[..., 0]
    return k


def matrix_from_rotvec(rotvec: ArrayLike) -> F64:
    """exp([phi]_x) for a rotation vector phi (rad), shape (3,) -> (3, 3)."""
    phi = np.asarray(rotvec, dtype=float)
    th = float(np.linalg.norm(phi))
    k = skew(phi)
    if th < 1e-8:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + np.sin(th) / th * k + (1.0 - np.cos(th)) / th**2 * k @ k


def left_jacobian(rotvec: ArrayLike) -> F64:
    """Left Jacobian of SO(3): d exp(phi) = [J_l(phi) dphi]_x exp(phi), shape (..., 3) ->
    (..., 3, 3) (a batch at once: one NumPy pass, no loop over the rotations)."""
    phi = np.asarray(rotvec, dtype=float)
    th = np.linalg.norm(phi, axis=-1)[..., None, None]
    k = skew(phi)
    kk = k @ k
    small = th < 1e-6
    safe = np.where(small, 1.0, th)
    big = np.eye(3) + (1.0 - np.cos(safe)) / safe**2 * k + (safe - np.sin(safe)) / safe**3 * kk
    if not small.any():
        return big
    return np.where(small, np.eye(3) + 0.5 * k + kk / 6.0, big)


def rotation_angle(a: ArrayLike, b: ArrayLike) -> F64:
    """Angle of the rotation between frames ``a`` and ``b`` (rad), shapes (..., 3, 3) -> (...).

    Uses atan2(|vee(E - E^T)| / 2, (tr E - 1) / 2) with E = a^T b, accurate near zero (no
    arccos of a number close to 1).
    """
    e = np.swapaxes(np.asarray(a, dtype=float), -1, -2) @ np.asarray(b, dtype=float)
    w = np.stack([e[..., 2, 1] - e[..., 1, 2], e[..., 0, 2] - e[..., 2, 0],
                  e[..., 1, 0] - e[..., 0, 1]], axis=-1)
    s = 0.5 * np.linalg.norm(w, axis=-1)
    c = 0.5 * (np.trace(e, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(s, c)
