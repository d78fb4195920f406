"""What is drawn over the scene of a comparison video: the colour scheme and its legend, the
noise floor below which values print as 0, the deviation arrow and the live delta_p(t) plot.

The deviation arrow is painted onto the read image (:func:`paint_arrow`), not added to the 3D
scene: its two ends are the nominal and the (magnified) actual tool points, both inside the
wrist of the arms drawn, which hid a 3D arrow in every frame. The legend names the arrow only
on frames where it is painted (:func:`legend_text`)."""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64, U8

__all__ = ["ARROW_RGB_U8", "MIN_ARROW_PX", "NOISE_FLOOR", "PANEL_PX", "delta_p_figure",
           "legend_text", "paint_arrow", "shown_value"]


DESIRED_RGBA = (0.2, 0.9, 0.3, 1.0)
ACTUAL_RGBA = (1.0, 0.2, 0.85, 1.0)
EARLIER_RGBA = (0.65, 0.25, 0.6, 0.8)
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


def legend_text(magnify: float, arm_magnified: bool, arrow: bool) -> str:
    """The colour legend of one frame: the arrow's line only when ``arrow`` (painted on it;
    otherwise an empty line, so that the legend does not jump between frames)."""
    lines = ["green: desired path (nominal)", f"magenta: actual path x{magnify:g}",
             f"yellow arrow: deviation x{magnify:g}" if arrow else "",
             "white ghost: nominal arm",
             "orange: perturbed arm" + (f", errors x{magnify:g}" if arm_magnified else "")]
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
