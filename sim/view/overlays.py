"""What is drawn over the scene of a comparison video: the colour scheme and its legend, the
noise floor below which values print as 0, and the live delta_p(t) plot."""

from __future__ import annotations

import mujoco

from zrp.arrays import F64

__all__ = ["LEGEND", "NOISE_FLOOR", "PANEL_PX", "delta_p_figure", "shown_value"]


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
LEGEND = ("green: desired path (nominal)\nmagenta: actual path x{m:g}\nyellow arrow: "
          "deviation x{m:g}\nwhite ghost: nominal arm\norange: perturbed arm{arm}")


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
