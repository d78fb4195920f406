"""Simulation layer: MuJoCo playback and consistency checks against ZRP (:mod:`.playback`),
servo dynamics (:mod:`.dynamics`), offscreen rendering and video (:mod:`.gl`, :mod:`.render`,
:mod:`.video`), the physics "real" robot (:mod:`.real_robot`), its measuring procedure
(:mod:`.measurement`) and the blind benchmark of the gap diagnosis (:mod:`.benchmark`).

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

_EXPORTS = {
    "dynamics": (
        "DynamicPlayback",
        "default_dynamic_options",
        "dynamic_playback",
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
        "parse_effects",
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
        "EFFECT_NAMES",
        "HiddenEffects",
        "Reading",
        "RealRobot",
        "RealRobotOptions",
        "Session",
        "default_tool_points",
        "motor_map",
        "true_geometry",
    ),
    "render": (
        "OffscreenRenderer",
    ),
    "video": (
        "PAPER_LEVELS",
        "VideoOptions",
        "VideoResult",
        "VideoWriteError",
        "comparison_frames",
        "nice_factor",
        "render_comparison_video",
        "render_paper_video",
        "render_teaching_sweep",
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
