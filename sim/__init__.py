"""Simulation layer: MuJoCo playback and consistency checks against ZRP (:mod:`.playback`),
servo dynamics (:mod:`.dynamics`), offscreen rendering (:mod:`.gl`, :mod:`.render`), comparison
frames and videos (:mod:`.frames`, :mod:`.video`), the physics "real" robot (its hidden
effects :mod:`.effects` and their text specs :mod:`.effect_specs`, its MuJoCo model
:mod:`.robot_model`, the robot and its controller :mod:`.real_robot`), its measuring procedure
(:mod:`.measurement`) and the blind benchmark of the gap diagnosis (the package
:mod:`.benchmark`, imported by name: ``from sim.benchmark import run_benchmark``).

What a video shows is the caller's choice: the paper's scenes are assembled in the core
(:mod:`zrp.paper.scenes`) and passed to :func:`render_video` as segments.

MuJoCo fixes its GL backend when it is first imported; :mod:`sim.gl` imports
``mujoco.egl``/``mujoco.osmesa`` directly, so :class:`OffscreenRenderer` works whatever was
imported first.

Names load on first use (PEP 562), so ``import sim`` does not import ``mujoco``: that lets
:func:`configure_backend` choose the backend before MuJoCo fixes it at its first import, for
``mujoco.Renderer`` too. No submodule shares a name with a function, so ``from sim import X``
gives the same object whatever was imported before (tested).
"""

from __future__ import annotations

import importlib
from typing import Any

from zrp.environment import check_mujoco_gl

# MuJoCo fails at import on an unknown MUJOCO_GL: say so as a named error first (no mujoco
# import here; zrp.environment is plain Python).
check_mujoco_gl()

_EXPORTS = {
    "dynamics": (
        "DynamicPlayback",
        "default_dynamic_options",
        "dynamic_playback",
    ),
    "effect_specs": (
        "parse_effects",
    ),
    "effects": (
        "EFFECT_NAMES",
        "HiddenEffects",
        "default_tool_points",
        "motor_map",
        "true_geometry",
    ),
    "frames": (
        "VideoOptions",
        "VideoSegment",
        "comparison_frames",
        "nice_factor",
        "video_frames",
    ),
    "framing": (
        "frame_on_path",
        "framing_report",
        "path_normal",
        "projected_fractions",
    ),
    "viewer": (
        "DisplayUnavailableError",
        "display_status",
        "view_path",
    ),
    "gl": (
        "BACKENDS",
        "GLBackendError",
        "GLUnavailableError",
        "available_backend",
        "configure_backend",
        "probe_backend",
        "resolve_backend",
    ),
    "measurement": (
        "Instrument",
        "MeasurementRun",
        "Procedure",
        "measure",
        "random_instrument",
        "trajectory_poses",
        "write_measurements",
        "write_truth",
    ),
    "playback": (
        "ConsistencyReport",
        "SitePoses",
        "consistency_check",
        "kinematic_playback",
    ),
    "real_robot": (
        "Reading",
        "RealRobot",
        "Session",
    ),
    "render": (
        "OffscreenRenderer",
    ),
    "robot_model": (
        "RealRobotOptions",
    ),
    "video": (
        "VideoResult",
        "VideoWriteError",
        "render_comparison_video",
        "render_video",
        "video_path",
    ),
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
