"""MuJoCo's interactive viewer playing a joint path (``zrp view``), where a display exists.

The perturbed arm moves along the joint path q(t) in a loop; the desired path (nominal direct
kinematics) is drawn in green in the viewer's user scene and the actual tool path, magnified
about it, in magenta (the colours of the videos, :mod:`sim.view.overlays`). Without a display
(no ``DISPLAY`` / ``WAYLAND_DISPLAY`` on Linux, or a GLFW that cannot open a window) the
call raises :class:`DisplayUnavailableError` with what to do instead.
"""

from __future__ import annotations

import itertools
import os
import sys
import time

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf import MJCFOptions, build
from sim.view.overlays import ACTUAL_RGBA, ARM_RGBA, DESIRED_RGBA
from sim.view.playback import kinematic_playback
from zrp.errors import InputError, ZRPError
from zrp.model.manipulator import Manipulator

__all__ = ["DisplayUnavailableError", "display_status", "view_path"]


class DisplayUnavailableError(ZRPError, RuntimeError):
    """No display for the interactive viewer (the message says what to use instead)."""


_INSTEAD = ("use `zrp render` (an offscreen video) instead, or run where a display exists "
            "(a desktop session, or `xvfb-run zrp view` / ssh -X)")


def display_status() -> tuple[bool, str]:
    """(whether a display seems available, why): on Linux it needs DISPLAY or
    WAYLAND_DISPLAY; macOS and Windows always have one."""
    if sys.platform == "darwin" or sys.platform.startswith("win"):
        return True, f"{sys.platform} desktop"
    for var in ("DISPLAY", "WAYLAND_DISPLAY"):
        if os.environ.get(var):
            return True, f"{var}={os.environ[var]}"
    return False, "no display: neither DISPLAY nor WAYLAND_DISPLAY is set"


def _add_line(scn: mujoco.MjvScene, a: np.ndarray, b: np.ndarray, rgba: tuple) -> None:
    if scn.ngeom >= scn.maxgeom:
        return
    g = scn.geoms[scn.ngeom]
    mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3),
                        np.eye(3).ravel(), np.asarray(rgba, dtype=np.float32))
    mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, 3.0, a, b)
    scn.ngeom += 1


def view_path(nominal: Manipulator, perturbed: Manipulator, t: ArrayLike, q: ArrayLike, *,
              magnify: float = 1.0, loops: int | None = None) -> None:
    """Play ``q(t)`` (t in s, shape (N,); q rad, shape (N, n)) on ``perturbed`` in MuJoCo's
    viewer, the desired path of ``nominal`` and the actual path (deviations x ``magnify``)
    drawn; until the window is closed, or ``loops`` times round.

    Raises:
        DisplayUnavailableError: no display (see :func:`display_status`) or the viewer cannot
            open a window.
    """
    ok, why = display_status()
    if not ok:
        raise DisplayUnavailableError(f"zrp view: {why}; {_INSTEAD}")
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if t.ndim != 1 or q.shape[0] != t.size or t.size < 2:
        raise InputError(f"t, q: expected shapes (N,) and (N, n), got {t.shape}, {q.shape}")
    arm = build(perturbed, MJCFOptions(link_rgba=ARM_RGBA))
    des = kinematic_playback(build(nominal, MJCFOptions()), q).position * arm.scale   # m
    act = kinematic_playback(arm, q).position * arm.scale
    shown = des + magnify * (act - des)
    try:
        import mujoco.viewer  # GLFW: only when a window is wanted
        handle = mujoco.viewer.launch_passive(arm.model, mujoco.MjData(arm.model))
    except Exception as exc:  # GLFW missing, or the display refuses a window
        raise DisplayUnavailableError(f"zrp view: the viewer cannot open a window ({exc}); "
                                      f"{_INSTEAD}") from exc
    data = mujoco.MjData(arm.model)
    idx = np.linspace(0, len(t) - 1, min(len(t), 200)).astype(int)
    with handle as viewer:
        with viewer.lock():
            viewer.user_scn.ngeom = 0
            for path, rgba in ((des, DESIRED_RGBA), (shown, ACTUAL_RGBA)):
                for i, j in itertools.pairwise(idx):
                    _add_line(viewer.user_scn, path[i], path[j], rgba)
        done = 0
        while viewer.is_running() and (loops is None or done < loops):
            start = time.perf_counter()
            for k in range(len(t)):
                if not viewer.is_running():
                    break
                data.qpos[arm.qpos_adr] = arm.qpos(q[k])
                mujoco.mj_kinematics(arm.model, data)
                with viewer.lock():
                    viewer.d.qpos[:] = data.qpos
                    mujoco.mj_forward(viewer.m, viewer.d)
                viewer.sync()
                time.sleep(max(0.0, (t[k] - t[0]) - (time.perf_counter() - start)))
            done += 1
