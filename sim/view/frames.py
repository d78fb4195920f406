"""Frames of a nominal and a perturbed arm following the same joint trajectory.

Each frame shows the perturbed ("actual") arm (orange links), the nominal arm as a translucent
white ghost, the desired path (nominal direct kinematics, green), the actual path (magenta) and
the current deviation vector (a yellow arrow painted over the image), both magnified about the
desired path by one stated factor for the whole video, a colour legend that names each element
only on the frames where it is visible (one rule, :func:`sim.view.overlays.visible_in_frame`;
what is not visible is not drawn either, :mod:`sim.view.frame_scene`), a text block with the
perturbation, delta_p, delta_R (eq 15) and theta (values below :data:`NOISE_FLOOR` print as 0,
and the floor is stated), and a live plot of delta_p(t). In a video of several segments (a
sweep over levels) the actual paths of the earlier segments stay drawn, dimmed.

The camera looks along the normal of the desired path's plane (:mod:`sim.view.framing`), so a
circle appears round, and frames the arm and the path together; the floor and the pedestal
are hidden (seen edge on they only hid the text).

The input is a sequence of segments (:class:`VideoSegment`: two models, a joint path q(t) and a
label); what the models are and where the joint path comes from is the caller's business (the
paper's scenes: :mod:`zrp.paper.scenes`). Desired = nominal model's pose, actual = perturbed
model's pose at the same joint values (the paper's definition). Poses are MuJoCo's (the
consistency tests check they equal ZRP direct kinematics to ~1e-13 mm). Encoding and files:
:mod:`sim.view.video`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf import BuiltArm, MJCFOptions, build
from sim.robot.dynamics import check_timed_q
from sim.view.frame_scene import HIDDEN_GROUP, draw_scene, hide_triad, tool_radius_m
from sim.view.framing import frame_on_path
from sim.view.gl import _check_name
from sim.view.magnify import exaggerated_model as exaggerated_model
from sim.view.magnify import nice_factor as nice_factor
from sim.view.overlays import (
    ARM_RGBA,
    GHOST_RGBA,
    NOISE_FLOOR,
    PANEL_PX,
    delta_p_figure,
    legend_text,
    paint_arrow,
    shown_value,
)
from sim.view.playback import kinematic_playback
from sim.view.render import OffscreenRenderer
from zrp.arrays import F64, U8
from zrp.errors import InputError, ZRPError
from zrp.model.manipulator import Manipulator
from zrp.rotations import rotation_angle

__all__ = [
    "FORMATS",
    "VideoOptions",
    "VideoSegment",
    "comparison_frames",
    "exaggerated_model",
    "nice_factor",
    "video_frames",
]

FORMATS = ("auto", "mp4", "gif")

class VideoSegment(NamedTuple):
    """One part of a video: ``nominal`` (ghost) and ``perturbed`` arm along the joint path
    ``q(t)`` (t in s, shape (N,); q shape (N, n), usually the nominal inverse kinematics),
    titled ``label``. Any 5-tuple in this order works too."""

    nominal: Manipulator
    perturbed: Manipulator
    t: ArrayLike
    q: ArrayLike
    label: str = ""


@dataclass(frozen=True)
class VideoOptions:
    """Video settings.

    Attributes:
        width, height: pixels.
        fps: frames per second of the output.
        seconds: video length per segment, s; None = the trajectory's duration.
        magnify: factor applied to deviations in the drawing; None = a round number that makes
            the largest deviation about a quarter of the path's size.
        format: "mp4" (libx264 through imageio-ffmpeg), "gif", or "auto" (mp4, else gif).
        backend: "egl", "osmesa" or None (MUJOCO_GL, else the first that works).
        trace_segments: line segments per drawn path.
        ghost_alpha: opacity of the nominal arm.
        fill: fraction of the free part of the frame (between the text panels) the arm and
            the path take together (the camera looks along the path plane's normal,
            :func:`sim.view.framing.frame_on_path`).
        plot: draw the live delta_p plot.
        exaggerate_arm: draw the perturbed arm with its parameter errors multiplied by the
            magnification too (see :func:`exaggerated_model`), so it visibly leaves the ghost
            and its tool point follows the magnified red path (to first order). Numbers on
            the video are always those of the true perturbation.
    """

    width: int = 640
    height: int = 480
    fps: int = 30
    seconds: float | None = None
    magnify: float | None = None
    format: str = "auto"
    backend: str | None = None
    trace_segments: int = 120
    ghost_alpha: float = 0.35
    fill: float = 0.92
    plot: bool = True
    exaggerate_arm: bool = True

    def __post_init__(self) -> None:
        for name in ("width", "height", "fps", "trace_segments"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
                raise InputError(f"{name}: expected a positive integer, got {v!r}")
        _check_positive_or_none(self.seconds, "seconds", "a positive duration (s) or None")
        _check_positive_or_none(self.magnify, "magnify", "a positive factor or None (auto)")
        if self.format not in FORMATS:
            raise InputError(f"format: unknown video format {self.format!r}; expected one of "
                             f"{FORMATS}")
        if not 0 < self.ghost_alpha <= 1:
            raise InputError(f"ghost_alpha: expected an opacity in (0, 1], got "
                             f"{self.ghost_alpha!r}")
        if not 0 < self.fill < 1:
            raise InputError(f"fill: expected a fraction of the frame height in (0, 1), got "
                             f"{self.fill!r}")
        if self.backend is not None:
            _check_name(self.backend, "backend")


def _check_positive_or_none(value: float | None, name: str, expected: str) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected {expected}, got {value!r}")


# ---- one segment -------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Segment:
    nominal: BuiltArm
    actual: BuiltArm
    t: F64  # (F,) frame times, s
    q: F64  # (F, n)
    p_des: F64  # (F, 3) m
    p_act: F64  # (F, 3) m
    delta_p: F64  # (F,) model unit
    delta_r: F64  # (F,) eq 15
    theta: F64  # (F,) rad
    label: str
    drawn: BuiltArm | None = None  # the opaque arm drawn (perturbed, maybe exaggerated)


def _segment(nominal: Manipulator, perturbed: Manipulator, t: ArrayLike, q: ArrayLike,
             frames: int, label: str, ghost_alpha: float, size: tuple[int, int]) -> _Segment:
    if not isinstance(nominal, Manipulator) or not isinstance(perturbed, Manipulator):
        raise InputError("nominal, perturbed: expected zrp.Manipulator models")
    if (nominal.n != perturbed.n or nominal.joint_types != perturbed.joint_types
            or nominal.length_unit != perturbed.length_unit):
        raise InputError("nominal, perturbed: must have the same joints and length unit")
    t, q = check_timed_q(nominal, t, q)
    tf = np.linspace(t[0], t[-1], frames)
    qf = np.stack([np.interp(tf, t, q[:, j]) for j in range(nominal.n)], axis=1)
    arm_a = build(perturbed, MJCFOptions(offscreen_size=size, link_rgba=ARM_RGBA))
    arm_n = build(nominal, MJCFOptions(alpha=ghost_alpha, floor=False, prefix="ghost_",
                                       tint=GHOST_RGBA, offscreen_size=size))
    for arm in (arm_a, arm_n):
        hide_triad(arm)
    des = kinematic_playback(arm_n, qf)
    act = kinematic_playback(arm_a, qf)
    dp = np.linalg.norm(act.position - des.position, axis=-1)
    theta = rotation_angle(des.frame, act.frame)
    dr = 2.0 * math.sqrt(2.0) * np.sin(theta / 2.0)  # eq (15) = sqrt(4(1 - e0^2 + e.e))
    return _Segment(arm_n, arm_a, tf, qf, des.position * arm_n.scale,
                    act.position * arm_a.scale, dp, dr, theta, label)


def _arm_points(seg: _Segment) -> F64:
    """Body origins of the drawn arm at up to 24 frames of the segment (m), shape
    (frames, bodies, 3)."""
    arm = seg.drawn or seg.actual
    d = mujoco.MjData(arm.model)
    pts = []
    for f in np.linspace(0, len(seg.t) - 1, min(len(seg.t), 24)).astype(int):
        d.qpos[arm.qpos_adr] = arm.qpos(seg.q[f])
        mujoco.mj_kinematics(arm.model, d)
        pts.append(d.xpos[1:].copy())
    return np.stack(pts)


def _camera(r: OffscreenRenderer, segs: Sequence[_Segment], opts: VideoOptions) -> None:
    """Look along the normal of the first path's plane and frame every arm and path
    (:func:`sim.view.framing.frame_on_path`); hide the floor and the pedestal (geom group 2)."""
    path = np.vstack([s.p_des for s in segs])
    arm = np.concatenate([_arm_points(s) for s in segs])
    # the scene left of the right-hand column of text and plot (PANEL_PX wide at font scale
    # 100) and below the two title lines
    w, h = opts.width, opts.height
    frame_on_path(r, path, arm.reshape(-1, 3),
                  box=(0.01, max(0.5, 1 - (PANEL_PX + 10) / w), 0.01, max(0.7, 1 - 55 / h)),
                  margin=opts.fill)
    r.option.geomgroup[2] = 0
    r.option.geomgroup[HIDDEN_GROUP] = 0
    r.option.frame = mujoco.mjtFrame.mjFRAME_NONE


def _magnified(seg: _Segment, magnify: float) -> F64:
    """The actual path drawn: desired + magnify (actual - desired), m, shape (F, 3)."""
    return seg.p_des + magnify * (seg.p_act - seg.p_des)


def _segment_frames(r: OffscreenRenderer, seg: _Segment, magnify: float, opts: VideoOptions,
                    unit: str, title: str, plot_top: float | None = None,
                    earlier: Sequence[F64] = (), legends: list[str] | None = None
                    ) -> Iterator[U8]:
    """The frames of one segment; ``earlier``: magnified actual paths of the segments before
    it (m, each shape (F, 3)), kept on screen dimmed; each frame's legend text is appended to
    ``legends`` when given."""
    drawn = seg.drawn or seg.actual
    m_a, m_n = drawn.model, seg.nominal.model
    d_a, d_n = mujoco.MjData(m_a), mujoco.MjData(m_n)
    n_frames = len(seg.t)
    magnified = _magnified(seg, magnify)
    stride = max(1, math.ceil((n_frames - 1) / opts.trace_segments))
    idx_all = np.unique(np.r_[np.arange(0, n_frames, stride), n_frames - 1])
    fig = delta_p_figure(seg.t, seg.delta_p, opts.plot, unit, plot_top)
    max_pts = len(fig.linedata[0]) // 2 if opts.plot else 0
    plot_idx = np.linspace(0, n_frames - 1, min(n_frames, max_pts)).astype(int) if opts.plot \
        else np.zeros(0, int)
    pw, ph = int(opts.width * 0.36), int(opts.height * 0.27)
    col = max(pw, PANEL_PX)   # the right-hand column: legend, numbers, plot
    numbers = (opts.width - col - 4, ph + 8, col, max(1, opts.height - ph - 8))
    size = np.array([opts.width, opts.height], dtype=float)
    earlier_drawn = list(earlier)
    tool = (drawn.site_id, tool_radius_m(drawn))
    for f in range(n_frames):
        d_a.qpos[drawn.qpos_adr] = drawn.qpos(seg.q[f])
        d_n.qpos[seg.nominal.qpos_adr] = seg.nominal.qpos(seg.q[f])
        mujoco.mj_kinematics(m_a, d_a)
        mujoco.mj_kinematics(m_n, d_n)
        done = idx_all[idx_all <= f]
        if len(done) and done[-1] != f:
            done = np.r_[done, f]
        paths = ([prev[idx_all[idx_all < len(prev)]] for prev in earlier_drawn],
                 seg.p_des[idx_all], magnified[done])
        shown, ends_px = draw_scene(r, (m_a, d_a), (m_n, d_n), paths,
                                     (seg.p_des[f], magnified[f]), size, tool)
        r.render()
        r.text(f"{title}\n{seg.label}",
               corner=mujoco.mjtGridPos.mjGRID_TOPLEFT)
        r.text(f"t\ndelta_p\ndelta_R (eq 15)\ntheta\n(< {NOISE_FLOOR:g} shown as 0)",
               f"{seg.t[f]:.2f} s\n{shown_value(seg.delta_p[f], '.4g')} {unit}\n"
               f"{shown_value(seg.delta_r[f], '.3e')}\n{shown_value(seg.theta[f], '.3e')} rad\n",
               corner=mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, viewport=numbers)
        legend = legend_text(magnify, seg.drawn is not None, shown)
        r.text(legend, corner=mujoco.mjtGridPos.mjGRID_TOPRIGHT)
        if opts.plot:
            plotted = plot_idx[plot_idx <= f]
            fig.linepnt[0] = len(plotted)
            if len(plotted):
                fig.linedata[0][0:2 * len(plotted):2] = seg.t[plotted]
                fig.linedata[0][1:2 * len(plotted):2] = seg.delta_p[plotted]
            r.figure(fig, opts.width - pw - 4, 4, pw, ph)
        image = r.read()
        if shown.arrow:
            paint_arrow(image, ends_px[0], ends_px[1])
        if legends is not None:
            legends.append(legend)
        yield image


@dataclass(frozen=True, eq=False)
class _Prepared:
    """Segments with their models built and played back, the magnification drawn and the
    common top of the delta_p plots (model unit)."""

    segments: tuple[_Segment, ...]
    magnify: float
    top: float

    @property
    def first_model(self) -> mujoco.MjModel:
        s = self.segments[0]
        return (s.drawn or s.actual).model

    @property
    def frames(self) -> int:
        return sum(len(s.t) for s in self.segments)


def _prepare(segments: Sequence[VideoSegment | tuple[Manipulator, Manipulator, ArrayLike,
                                                     ArrayLike, str]],
             opts: VideoOptions) -> _Prepared:
    """Build, play back and measure every segment; choose the magnification."""
    if len(segments) == 0:
        raise InputError("segments: expected at least one (nominal, perturbed, t, q, label)")
    segments = [VideoSegment(*s) for s in segments]
    size = (max(opts.width, 640), max(opts.height, 480))
    segs = []
    for nominal, perturbed, t, q, label in segments:
        t_arr = np.asarray(t, dtype=float)
        seconds = opts.seconds if opts.seconds is not None else float(t_arr[-1] - t_arr[0])
        frames = max(2, round(seconds * opts.fps))
        segs.append(_segment(nominal, perturbed, t, q, frames, label, opts.ghost_alpha, size))
    magnify = opts.magnify
    if magnify is None:
        worst = max(float(np.max(s.delta_p)) * s.nominal.scale for s in segs)
        span = max(float(np.linalg.norm(s.p_des.max(axis=0) - s.p_des.min(axis=0)))
                   for s in segs) or 0.25
        magnify = nice_factor(0.25 * span / worst) if worst > 0 else 1.0
    top = max(float(np.max(s.delta_p)) for s in segs)
    if opts.exaggerate_arm:
        drawn = []
        for s, seg_in in zip(segs, segments, strict=True):
            try:
                shown = exaggerated_model(seg_in.nominal, seg_in.perturbed, magnify)
            except ZRPError:  # a degenerate exaggeration: draw the true arm
                shown = seg_in.perturbed
            arm = build(shown, MJCFOptions(offscreen_size=size, link_rgba=ARM_RGBA))
            hide_triad(arm)
            drawn.append(replace(s, drawn=arm))
        segs = drawn
    return _Prepared(tuple(segs), magnify, top)


def _frames(prep: _Prepared, opts: VideoOptions, title: str, r: OffscreenRenderer,
            legends: list[str] | None = None) -> Iterator[U8]:
    segs = prep.segments
    unit = segs[0].nominal.manipulator.length_unit
    _camera(r, segs, opts)
    earlier: list[F64] = []
    for seg in segs:
        if (seg.drawn or seg.actual).model.nbody != r.model.nbody:
            raise InputError("segments: every perturbed model must have the same structure "
                             "as the first")
        yield from _segment_frames(r, seg, prep.magnify, opts, unit, title, prep.top,
                                   tuple(earlier), legends)
        earlier.append(_magnified(seg, prep.magnify))


def video_frames(segments: Sequence[VideoSegment], *, title: str = "nominal vs perturbed",
                 options: VideoOptions | None = None, legends: list[str] | None = None
                 ) -> Iterator[U8]:
    """The frames of :func:`sim.view.video.render_video` without encoding, each shape
    (height, width, 3) uint8 (e.g. for ``mediapy.show_video`` in a notebook). When
    ``legends`` is a list, each frame's legend text is appended to it as the frame is yielded
    (a line per element the frame shows, :func:`sim.view.overlays.visible_in_frame`).

    The GL context is freed when the generator finishes or is closed; use
    ``contextlib.closing(video_frames(...))`` when stopping early.
    """
    opts = options or VideoOptions()
    prep = _prepare(segments, opts)
    with OffscreenRenderer(prep.first_model, opts.width, opts.height,
                           backend=opts.backend) as r:
        yield from _frames(prep, opts, title, r, legends)


def comparison_frames(
    nominal: Manipulator,
    perturbed: Manipulator,
    t: ArrayLike,
    q: ArrayLike,
    *,
    label: str = "",
    title: str = "nominal vs perturbed",
    options: VideoOptions | None = None,
) -> Iterator[U8]:
    """:func:`video_frames` of one segment (the frames of
    :func:`sim.view.video.render_comparison_video`)."""
    return video_frames([VideoSegment(nominal, perturbed, t, q, label)], title=title,
                        options=options)
