"""MuJoCo playback, consistency checks and offscreen rendering of ZRP manipulators.

* :func:`kinematic_playback` / :func:`consistency_check`: MuJoCo site poses along a joint
  trajectory, and their agreement with :func:`zrp.forward_kinematics`.
* :func:`dynamic_playback`: PD servos tracking the trajectory under gravity.
* :class:`OffscreenRenderer`: EGL/OSMesa rendering with overlays, released deterministically.
* :func:`render_comparison_video`, :func:`render_paper_video`, :func:`render_teaching_sweep`.

Names are loaded lazily, so ``import sim`` does not import ``mujoco``: call
:func:`configure_backend` first when ``mujoco.Renderer`` should use the chosen backend too
(MuJoCo fixes its GL backend when it is first imported).
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "dynamics": ("DynamicPlayback", "default_dynamic_options", "dynamic_playback"),
    "measure": ("Instrument", "MeasurementRun", "Procedure", "measure", "parse_effects",
                "random_instrument", "random_poses", "trajectory_poses", "write_measurements",
                "write_truth"),
    "gl": ("BACKENDS", "GLBackendError", "GLUnavailableError", "available_backend",
           "configure_backend", "probe_backend", "resolve_backend"),
    "playback": ("ConsistencyReport", "SitePoses", "consistency_check", "kinematic_playback",
                 "rotation_angle"),
    "real_robot": ("EFFECT_NAMES", "HiddenEffects", "RealRobot", "RealRobotOptions", "Reading",
                   "Session", "default_tool_points", "motor_map", "true_geometry"),
    "render": ("OffscreenRenderer",),
    "video": ("PAPER_LEVELS", "VideoOptions", "VideoResult", "VideoWriteError",
              "comparison_frames", "nice_factor", "render_comparison_video",
              "render_paper_video", "render_teaching_sweep"),
}
_WHERE = {name: mod for mod, names in _EXPORTS.items() for name in names}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    mod = _WHERE.get(name)
    if mod is None:
        raise AttributeError(f"module 'sim' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{mod}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
