"""Simulation layer, in sub-packages by job (see sim/README.md):

* :mod:`sim.robot`: the physics "real" robot and its instrument - hidden effects
  (:mod:`~sim.robot.effects`, text specs :mod:`~sim.robot.effect_specs`), its MuJoCo model
  (:mod:`~sim.robot.model`), the robot and its controller at rest (:mod:`~sim.robot.real`) and
  in motion (:mod:`~sim.robot.motion`), servo dynamics (:mod:`~sim.robot.dynamics`), the
  laser tracker (:mod:`~sim.robot.instrument`) and the measuring procedures
  (:mod:`~sim.robot.measurement`, :mod:`~sim.robot.motion_measure`);
* :mod:`sim.view`: MuJoCo playback and its consistency check against ZRP
  (:mod:`~sim.view.playback`), offscreen rendering (:mod:`~sim.view.gl`,
  :mod:`~sim.view.render`), comparison frames and videos (:mod:`~sim.view.frames`,
  :mod:`~sim.view.video`, :mod:`~sim.view.motion_video`) and the interactive viewer;
* :mod:`sim.studies`: the blind benchmarks of the gap diagnosis (:mod:`sim.studies.benchmark`,
  imported by name: ``from sim.studies.benchmark import run_benchmark``), the planned-poses
  study and the compensation check;
* :mod:`sim.lessons`: runnable lessons, one concept each.

What a video shows is the caller's choice: the paper's scenes are assembled in the core
(:mod:`zrp.paper.scenes`) and passed to :func:`render_video` as segments. Likewise the
trajectories the robot is measured along are passed in: the studies and the command line build
the paper's circle (:mod:`sim.studies.trajectories`), :mod:`sim.robot` never imports the paper.

MuJoCo fixes its GL backend when it is first imported; :mod:`sim.view.gl` imports
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
from zrp.packages import DISTRIBUTION, check_own_packages

#: The distribution this ``sim`` belongs to (a generic name: see :mod:`zrp.packages`).
__distribution__ = DISTRIBUTION
check_own_packages(("mjcf",))  # a clear error if another 'mjcf' shadows ours

# MuJoCo fails at import on an unknown MUJOCO_GL: say so as a named error first (no mujoco
# import here; zrp.environment is plain Python).
check_mujoco_gl()

_EXPORTS = {
    "robot.dynamics": (
        "DynamicPlayback",
        "default_dynamic_options",
        "dynamic_playback",
    ),
    "robot.effect_specs": (
        "parse_effects",
    ),
    "robot.effects": (
        "EFFECT_NAMES",
        "HiddenEffects",
        "default_tool_points",
        "motor_map",
        "true_geometry",
    ),
    "robot.instrument": (
        "Instrument",
        "random_instrument",
    ),
    "robot.mass": (
        "DynamicsFallbackWarning",
    ),
    "robot.measurement": (
        "MeasurementRun",
        "Procedure",
        "measure",
        "trajectory_poses",
        "write_measurements",
        "write_truth",
    ),
    "robot.model": (
        "RealRobotOptions",
    ),
    "robot.real": (
        "Reading",
        "RealRobot",
        "Session",
    ),
    "robot.servo": (
        "tune_servos",
    ),
    "view.frames": (
        "VideoOptions",
        "VideoSegment",
        "comparison_frames",
        "nice_factor",
        "video_frames",
    ),
    "view.framing": (
        "frame_on_path",
        "framing_report",
        "path_normal",
        "projected_fractions",
    ),
    "view.gl": (
        "BACKENDS",
        "GLBackendError",
        "GLUnavailableError",
        "available_backend",
        "configure_backend",
        "probe_backend",
        "resolve_backend",
    ),
    "view.playback": (
        "ConsistencyReport",
        "SitePoses",
        "consistency_check",
        "kinematic_playback",
    ),
    "view.render": (
        "OffscreenRenderer",
    ),
    "view.video": (
        "VideoResult",
        "VideoWriteError",
        "render_comparison_video",
        "render_video",
        "video_path",
    ),
    "view.viewer": (
        "DisplayUnavailableError",
        "display_status",
        "view_path",
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
