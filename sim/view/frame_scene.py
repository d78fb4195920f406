"""What one frame of a comparison video draws in 3D: the arm, the ghost unless it coincides
with the arm, and the paths, each only when visible (the legend's one rule,
:func:`sim.view.overlays.visible_in_frame`, from where they land on the screen), and the
end effector's triad kept out of the picture. Used by :mod:`sim.view.frames`."""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf import BuiltArm
from sim.view.framing import projected_fractions
from sim.view.overlays import (
    ACTUAL_RGBA,
    DESIRED_RGBA,
    EARLIER_RGBA,
    Visible,
    visible_in_frame,
)
from sim.view.render import OffscreenRenderer
from zrp.arrays import F64

__all__ = ["HIDDEN_GROUP", "draw_scene", "hide_triad", "tool_radius_m"]

#: Geom group of the end effector's triad in the videos, never rendered (geomgroup off).
HIDDEN_GROUP = 5


def hide_triad(arm: BuiltArm) -> None:
    """Keep the end effector's RGB triad out of the picture (its red axis looked like the
    deviation): in a geom group the videos do not render, since a transparent geom still
    writes depth and hid the paths near the tool point."""
    for g in range(arm.model.ngeom):
        if "hand_" in (mujoco.mj_id2name(arm.model, mujoco.mjtObj.mjOBJ_GEOM, g) or ""):
            arm.model.geom_rgba[g, 3] = 0.0
            arm.model.geom_group[g] = HIDDEN_GROUP


def tool_radius_m(arm: BuiltArm) -> float:
    """Radius (m) of the arm's tool end: the largest sphere or capsule (its end cap) of the
    end effector's body that is rendered; 0 when it has none."""
    m = arm.model
    body = m.site_bodyid[arm.site_id]
    round_ = (int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CAPSULE))
    radii = [float(m.geom_size[g, 0]) for g in range(m.ngeom)
             if m.geom_bodyid[g] == body and int(m.geom_type[g]) in round_
             and m.geom_group[g] != HIDDEN_GROUP]
    return max(radii, default=0.0)


def draw_scene(r: OffscreenRenderer, arm: tuple[mujoco.MjModel, mujoco.MjData],
                ghost: tuple[mujoco.MjModel, mujoco.MjData],
                paths: tuple[Sequence[F64], F64, F64], arrow: tuple[F64, F64],
                size: F64, tool: tuple[int, float]) -> tuple[Visible, F64]:
    """Set up one frame's scene: the arm, the ghost unless it coincides with the arm, and the
    paths (m): earlier segments' (dimmed), desired, actual so far, in that order, each over
    the ones before, and each only when visible (the legend names what is drawn). Returns
    what the frame shows (:func:`sim.view.overlays.visible_in_frame`, the legend's one rule)
    and the arrow's ends (pixels from the top left). ``tool``: the arm's end-effector site
    and the radius of its tool end (m, :func:`tool_radius_m`)."""
    (m_a, d_a), extra = arm, [ghost]
    earlier, desired, actual = paths
    r.update_scene(d_a, [], model=m_a)   # sets the camera the pixels are computed with

    def px(points: ArrayLike) -> F64:
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        if len(pts) == 0:
            return np.zeros((0, 2))
        fr = projected_fractions(r.scene, pts, size[0] / size[1])
        return np.stack([fr[:, 0], 1.0 - fr[:, 1]], axis=1) * size

    nb = min(len(d_a.xpos), len(ghost[1].xpos))
    ends_px = px(np.stack(arrow))
    tip = d_a.site_xpos[tool[0]]
    tip_px = px(np.stack([tip, tip + tool[1] * np.asarray(r.scene.camera[0].up, float)]))
    shown = visible_in_frame(px(desired), px(actual), [px(e) for e in earlier], ends_px,
                             px(d_a.xpos[1:nb]), px(ghost[1].xpos[1:nb]),
                             (tip_px[0], float(np.linalg.norm(tip_px[1] - tip_px[0]))))
    if shown.ghost:
        r.update_scene(d_a, extra, model=m_a)
    # where two lines meet at equal depth the one added later is seen (added the other way
    # round, coinciding paths mixed their colours)
    for prev, drawn in zip(earlier, shown.earlier, strict=True):
        if drawn:
            r.add_polyline(prev, EARLIER_RGBA, 1.5)
    if shown.desired:
        r.add_polyline(desired, DESIRED_RGBA, 2.0)
    if shown.actual:
        r.add_polyline(actual, ACTUAL_RGBA, 2.5)
    return shown, ends_px
