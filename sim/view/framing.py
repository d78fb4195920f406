"""Framing a video on the circle: the camera normal to the path's plane, the arm filling the
frame, and the check that it does.

:func:`frame_on_path` points MuJoCo's free camera along the normal of the desired path's
best-fit plane (from outside the arm, looking back at it), so a circle projects as a circle,
and sets the distance so that the arm and the path together fill ``fill`` of the frame height.
:func:`projected_fractions` projects points through the GL camera MuJoCo actually drew with
(``scene.camera[0]``: position, forward, up, frustum), giving their extent as fractions of the
frame: what :func:`framing_report` and the tests use to check that the framing holds.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from sim.view.render import OffscreenRenderer
from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["frame_on_path", "framing_report", "path_normal", "projected_fractions"]



def path_normal(path: ArrayLike) -> F64:
    """Unit normal of the best-fit plane of ``path`` (m, shape (M, 3), M >= 3), pointing away
    from the base origin (the side a camera looks back from at the arm)."""
    p = np.asarray(path, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 3:
        raise InputError(f"path: expected shape (M, 3) with M >= 3, got {p.shape}")
    c = p.mean(axis=0)
    n = np.linalg.svd(p - c)[2][-1]
    return n if n @ c >= 0 else -n


def _basis(forward: F64) -> tuple[F64, F64]:
    """(right, up) of a camera looking along ``forward`` with world +z up."""
    up0 = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
    right = np.cross(forward, up0)
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward)


def frame_on_path(r: OffscreenRenderer, path: ArrayLike, arm_points: ArrayLike,
                  box: tuple[float, float, float, float] = (0.2, 0.8, 0.2, 0.8),
                  margin: float = 0.92) -> None:
    """Camera normal to the path's plane, framing the arm and the path.

    Args:
        r: the renderer whose free camera is set.
        path: desired path, m, shape (M, 3).
        arm_points: points of the arm over the whole video (body origins), m, shape (K, 3).
        box: the part of the frame the union of both is fitted into, (left, right, bottom,
            top) as fractions of the frame (x from the left, y from the bottom): the rest is
            left to the text panels.
        margin: fraction of the box the union takes (the rest is a border).
    """
    x0, x1, y0, y1 = (float(v) for v in box)
    if not (0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1 and 0 < margin <= 1):
        raise InputError(f"box, margin: expected 0 <= left < right <= 1, 0 <= bottom < top <= "
                         f"1 and 0 < margin <= 1, got {box!r}, {margin!r}")
    p = np.asarray(path, dtype=float)
    pts = np.vstack([p, np.asarray(arm_points, dtype=float).reshape(-1, 3)])
    forward = -path_normal(p)
    right, up = _basis(forward)
    x, y = pts @ right, pts @ up
    centre = (0.5 * (x.max() + x.min()) * right + 0.5 * (y.max() + y.min()) * up
              + float(np.mean(p @ forward)) * forward)
    tan_half = math.tan(math.radians(float(r.model.vis.global_.fovy)) / 2.0)
    aspect = r.width / r.height
    # visible height H at the target: the union's height takes margin (y1 - y0) H, its
    # width at most margin (x1 - x0) aspect H
    height = max((y.max() - y.min()) / (y1 - y0),
                 (x.max() - x.min()) / ((x1 - x0) * aspect)) / margin
    distance = 0.5 * height / tan_half
    centre = (centre + (0.5 - 0.5 * (x0 + x1)) * height * aspect * right
              + (0.5 - 0.5 * (y0 + y1)) * height * up)
    az = math.degrees(math.atan2(forward[1], forward[0]))
    el = math.degrees(math.asin(float(np.clip(forward[2], -1.0, 1.0))))
    r.look_at(centre, distance, az, float(np.clip(el, -89.0, 89.0)))


def projected_fractions(scene: mujoco.MjvScene, points: ArrayLike, aspect: float) -> F64:
    """Where ``points`` (m, shape (K, 3)) land in the last drawn frame: shape (K, 2), columns
    x (0 = left, 1 = right) and y (0 = bottom, 1 = top) as fractions of the frame, through the
    GL camera of ``scene`` (call after ``update_scene``); ``aspect`` = width / height (MuJoCo
    sets the frustum's half-width from it when ``frustum_width`` is 0, as for free cameras)."""
    cam = scene.camera[0]
    pos, fwd, up = (np.asarray(cam.pos, float), np.asarray(cam.forward, float),
                    np.asarray(cam.up, float))
    right = np.cross(fwd, up)
    v = np.asarray(points, dtype=float).reshape(-1, 3) - pos
    depth = v @ fwd
    if np.any(depth <= 0):
        raise InputError("points: some lie behind the camera")
    xn = cam.frustum_near * (v @ right) / depth
    yn = cam.frustum_near * (v @ up) / depth
    half_w = cam.frustum_width or 0.5 * (cam.frustum_top - cam.frustum_bottom) * aspect
    fx = (xn - (cam.frustum_center - half_w)) / (2.0 * half_w)
    fy = (yn - cam.frustum_bottom) / (cam.frustum_top - cam.frustum_bottom)
    return np.stack([fx, fy], axis=1)


def framing_report(scene: mujoco.MjvScene, path: ArrayLike, arm_points: ArrayLike,
                   width: int, height: int) -> dict[str, float]:
    """Framing figures of the drawn frame: ``circle_aspect`` (projected width / height of the
    path, in pixels; 1 for a circle seen face on), ``arm_height_fraction`` (the smallest, over
    the frames of ``arm_points`` (m, shape (F, bodies, 3)), vertical extent of the arm's body
    origins / frame height) and ``path_height_fraction``."""
    fp = projected_fractions(scene, path, width / height)
    arm = np.asarray(arm_points, dtype=float)
    arm = arm.reshape(1, -1, 3) if arm.ndim == 2 else arm
    heights = [float(np.ptp(np.clip(projected_fractions(scene, a, width / height)[:, 1],
                                    0.0, 1.0))) for a in arm]
    w = (fp[:, 0].max() - fp[:, 0].min()) * width
    h = (fp[:, 1].max() - fp[:, 1].min()) * height
    return {"circle_aspect": float(w / h) if h > 0 else float("inf"),
            "arm_height_fraction": min(heights),
            "path_height_fraction": float(h / height)}
