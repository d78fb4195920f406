"""What is drawn over the scene of a comparison video: the colour scheme and its legend, the
noise floor below which values print as 0, the deviation arrow and the live delta_p(t) plot.

What the legend of a frame names is decided in one place, :func:`visible_in_frame`, from
where the elements land on the screen (pixels): a path is named when at least
:data:`MIN_PATH_PX` of it is drawn and not under a line drawn over it; the ghost is drawn and
named only when the arm leaves it (else the arm alone is drawn, named "perturbed =
nominal"); the arrow when it is painted. :func:`legend_text` writes the lines from that.

The deviation arrow is painted onto the read image (:func:`paint_arrow`), not added to the 3D
scene: its two ends are the nominal and the (magnified) actual tool points, both inside the
wrist of the arms drawn, which hid a 3D arrow in every frame. The legend names the arrow only
on frames where it is painted (:func:`legend_text`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64, U8

__all__ = ["ARROW_RGB_U8", "COINCIDE_PX", "COVER_PX", "MIN_ARROW_PX", "MIN_PATH_PX",
           "NOISE_FLOOR", "PANEL_PX", "Visible", "delta_p_figure", "legend_text", "paint_arrow",
           "shown_value", "visible_in_frame"]


DESIRED_RGBA = (0.2, 0.9, 0.3, 1.0)
ACTUAL_RGBA = (1.0, 0.2, 0.85, 1.0)
#: Opaque (a translucent line is drawn after every opaque one, over the desired path).
EARLIER_RGBA = (0.5, 0.2, 0.47, 1.0)
ARROW_RGBA = (1.0, 0.85, 0.1, 1.0)
GHOST_RGBA = (0.95, 0.95, 0.95, 1.0)
ARM_RGBA = (0.9, 0.55, 0.2, 1.0)
#: Width of the right-hand column (legend, numbers, plot), pixels at font scale 100.
PANEL_PX = 250
#: Deviations below these print as 0 on the frames (mm-scale lengths are ~1e-13 at rounding).
NOISE_FLOOR = 1e-9
#: The arrow's colour as painted (pure, unlit: the tests look for it in the frames' pixels).
ARROW_RGB_U8 = tuple(round(255 * c) for c in ARROW_RGBA[:3])
#: Arrows shorter than this (pixels) are not painted, and the legend does not name them.
MIN_ARROW_PX = 6.0


#: A path with less than this length (pixels) drawn and uncovered is not named.
MIN_PATH_PX = 6.0
#: A line point within this distance (pixels) of a line drawn over it is hidden by it.
COVER_PX = 2.0
#: The arm and the ghost coincide when no body origin of one is this far (pixels) from the other's.
COINCIDE_PX = 2.0


@dataclass(frozen=True)
class Visible:
    """What one frame shows and draws (each True only when visible on screen; what is not
    visible is not drawn either): the desired (green), actual (magenta) and each earlier
    segment's (purple) path; ``on_desired``: the actual path
    drawn lies on the desired one everywhere; the arrow; the ghost (False: it coincides with
    the arm and is not drawn)."""

    desired: bool
    actual: bool
    earlier: tuple[bool, ...]
    on_desired: bool
    arrow: bool
    ghost: bool


def _distance_to_polyline(points: F64, line: F64) -> F64:
    """Distance (pixels) of each point (K, 2) to the polyline ``line`` (M, 2); inf if M < 2."""
    if len(line) < 2:
        return np.full(len(points), np.inf)
    a, b = line[:-1][None], line[1:][None]
    ab = b - a
    t = np.clip(((points[:, None] - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12),
                0.0, 1.0)
    return np.linalg.norm(points[:, None] - (a + t[..., None] * ab), axis=-1).min(axis=1)


def _uncovered_px(line: F64, covers: Sequence[F64], hidden: tuple[F64, float] | None = None
                  ) -> float:
    """Length (pixels) of the polyline ``line`` (M, 2) farther than :data:`COVER_PX` from
    every polyline in ``covers`` (drawn over it) and outside the disk ``hidden`` (centre,
    radius in pixels), measured on pieces of at most 1 pixel."""
    if len(line) < 2:
        return 0.0
    seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
    k = np.maximum(1, np.ceil(seg)).astype(int)
    frac = np.concatenate([(np.arange(n) + 0.5) / n for n in k])
    start = np.repeat(np.arange(len(seg)), k)
    mid = line[start] + frac[:, None] * (line[start + 1] - line[start])
    piece = np.repeat(seg / k, k)
    free = np.ones(len(mid), bool)
    for c in covers:
        free &= _distance_to_polyline(mid, c) > COVER_PX
    if hidden is not None:
        free &= np.linalg.norm(mid - np.asarray(hidden[0], float), axis=1) > hidden[1]
    return float(piece[free].sum())


def visible_in_frame(desired_px: ArrayLike, actual_px: ArrayLike,
                     earlier_px: Sequence[ArrayLike], arrow_px: ArrayLike,
                     arm_px: ArrayLike, ghost_px: ArrayLike,
                     tool: tuple[ArrayLike, float] | None = None) -> Visible:
    """The one rule of what a frame's legend names, from screen positions (pixels, (K, 2)
    each): the paths as drawn (the earlier segments' first, then the desired, then the
    actual path traced so far, each over the ones before), the arrow's two ends, the body
    origins of the arm drawn and of the ghost, and ``tool``: the disk (centre, radius) of the
    arm's tool end, which hides the paths passing through the tool point."""
    des = np.asarray(desired_px, float).reshape(-1, 2)
    act = np.asarray(actual_px, float).reshape(-1, 2)
    earlier = [np.asarray(e, float).reshape(-1, 2) for e in earlier_px]
    ends = np.asarray(arrow_px, float).reshape(2, 2)
    arm, ghost = (np.asarray(x, float).reshape(-1, 2) for x in (arm_px, ghost_px))
    disk = None if tool is None else (np.asarray(tool[0], float).reshape(2), float(tool[1]))
    # from the top down: a line is hidden only by the lines drawn over it that are drawn
    actual = _uncovered_px(act, [], disk) >= MIN_PATH_PX
    over_des = [act] if actual else []
    desired = _uncovered_px(des, over_des, disk) >= MIN_PATH_PX
    over_earlier = over_des + ([des] if desired else [])
    return Visible(
        desired=desired,
        actual=actual,
        earlier=tuple(_uncovered_px(e, over_earlier, disk) >= MIN_PATH_PX for e in earlier),
        on_desired=actual and bool(np.all(_distance_to_polyline(act, des) <= COVER_PX)),
        arrow=bool(np.linalg.norm(ends[1] - ends[0]) >= MIN_ARROW_PX),
        ghost=bool(np.max(np.linalg.norm(arm - ghost, axis=1), initial=0.0) >= COINCIDE_PX))


def legend_text(magnify: float, arm_magnified: bool, shown: Visible) -> str:
    """The colour legend of one frame: a line per element of ``shown`` that is visible (an
    empty line otherwise, so that the legend does not jump between frames)."""
    m = f"x{magnify:g}"
    lines = ["green: desired path (nominal)" if shown.desired else "",
             ("magenta: actual = desired path" if shown.on_desired
              else f"magenta: actual path {m}") if shown.actual else "",
             f"yellow arrow: deviation {m}" if shown.arrow else "",
             "orange: perturbed arm" + (f", errors {m}" if arm_magnified else "")
             if shown.ghost else "orange: arm (perturbed = nominal)",
             "white ghost: nominal arm" if shown.ghost else "",
             "purple: earlier levels' paths" if any(shown.earlier) else ""]
    return "\n".join(lines)


def paint_arrow(image: U8, start_px: ArrayLike, end_px: ArrayLike,
                rgb: tuple[int, ...] = ARROW_RGB_U8, width_px: int = 4) -> bool:
    """Paint an arrow (shaft and a two-stroke head) from ``start_px`` to ``end_px`` (x, y in
    pixels from the top left) onto ``image`` (H, W, 3) in place; False, nothing painted,
    when it is shorter than :data:`MIN_ARROW_PX`."""
    a, b = np.asarray(start_px, dtype=float), np.asarray(end_px, dtype=float)
    length = float(np.linalg.norm(b - a))
    if not length >= MIN_ARROW_PX:
        return False
    back = (a - b) / length * min(14.0, 0.4 * length)
    c, s = np.cos(0.5), np.sin(0.5)  # head strokes at +-0.5 rad from the shaft
    heads = [b + np.array([c * back[0] - sg * s * back[1], sg * s * back[0] + c * back[1]])
             for sg in (1.0, -1.0)]
    pts = [np.linspace(p0, p1, int(np.linalg.norm(p1 - p0)) * 2 + 2)
           for p0, p1 in ((a, b), (b, heads[0]), (b, heads[1]))]
    r = width_px / 2.0
    off = np.array([(dx, dy) for dx in np.arange(-r, r + 0.5) for dy in np.arange(-r, r + 0.5)
                    if dx * dx + dy * dy <= r * r + 0.25])
    px = np.rint(np.concatenate(pts)[:, None, :] + off[None]).reshape(-1, 2).astype(int)
    h, w = image.shape[:2]
    keep = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
    image[px[keep, 1], px[keep, 0]] = rgb
    return True


def shown_value(value: float, fmt: str) -> str:
    """``value`` formatted, or 0 below :data:`NOISE_FLOOR`."""
    return "0" if abs(value) < NOISE_FLOOR else format(value, fmt)


def delta_p_figure(t: F64, delta_p: F64, plot: bool, unit: str, plot_top: float | None
                   ) -> mujoco.MjvFigure:
    """The live delta_p(t) plot (t in s, delta_p in ``unit``; empty when ``plot`` is off),
    its vertical range [0, 1.1 plot_top] (default the segment's largest delta_p)."""
    fig = mujoco.MjvFigure()
    if not plot:
        return fig
    mujoco.mjv_defaultFigure(fig)
    fig.flg_extend = 0
    fig.flg_ticklabel[0] = 1
    fig.flg_ticklabel[1] = 1
    fig.gridsize[:] = [3, 3]
    fig.title = f"delta_p ({unit})"
    fig.xlabel = "t (s)"
    fig.range[0][:] = [t[0], t[-1]]
    top = plot_top if plot_top is not None else float(delta_p.max())
    fig.range[1][:] = [0.0, 1.1 * (top or 1e-12)]
    fig.linergb[0][:] = ACTUAL_RGBA[:3]
    fig.figurergba[:] = [0.05, 0.05, 0.08, 0.85]
    fig.panergba[:] = [0.12, 0.12, 0.15, 1.0]
    fig.linewidth = 2.0
    fig.legendrgba[3] = 0.0
    return fig
