"""MuJoCo playback, consistency checks and offscreen rendering of ZRP manipulators.

* :func:`kinematic_playback` / :func:`consistency_check`: MuJoCo site poses along a joint
  trajectory, and their agreement with :func:`zrp.forward_kinematics`.
* :func:`dynamic_playback`: position servos tracking the trajectory under gravity.
* :class:`OffscreenRenderer`: EGL/OSMesa rendering with overlays, released deterministically.
* :func:`render_comparison_video`, :func:`render_paper_video`, :func:`render_teaching_sweep`.
"""

from .dynamics import DynamicPlayback, default_dynamic_options, dynamic_playback
from .gl import (
    BACKENDS,
    GLBackendError,
    GLUnavailableError,
    available_backend,
    probe_backend,
    resolve_backend,
)
from .playback import (
    ConsistencyReport,
    SitePoses,
    consistency_check,
    kinematic_playback,
    rotation_angle,
)
from .render import OffscreenRenderer
from .video import (
    PAPER_LEVELS,
    VideoOptions,
    VideoResult,
    VideoWriteError,
    nice_factor,
    render_comparison_video,
    render_paper_video,
    render_teaching_sweep,
)

__all__ = [
    "BACKENDS",
    "PAPER_LEVELS",
    "ConsistencyReport",
    "DynamicPlayback",
    "GLBackendError",
    "GLUnavailableError",
    "OffscreenRenderer",
    "SitePoses",
    "VideoOptions",
    "VideoResult",
    "VideoWriteError",
    "available_backend",
    "consistency_check",
    "default_dynamic_options",
    "dynamic_playback",
    "kinematic_playback",
    "nice_factor",
    "probe_backend",
    "render_comparison_video",
    "render_paper_video",
    "render_teaching_sweep",
    "resolve_backend",
    "rotation_angle",
]
