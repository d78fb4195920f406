"""Videos of a nominal and a perturbed arm following the same joint trajectory.

Each frame shows the perturbed ("actual") arm, the nominal arm as a translucent ghost, the
desired path (nominal direct kinematics, blue), the actual path (red) and the current deviation
vector (yellow arrow) both magnified about the desired path by a stated factor, a text block
with the perturbation, delta_p, delta_R (eq 15) and theta, and a live plot of delta_p(t).

The joint trajectory is the nominal inverse kinematics; desired = nominal model's pose, actual =
perturbed model's pose at the same joint values (the paper's definition). Poses are MuJoCo's
(the consistency tests check they equal ZRP direct kinematics to ~1e-13 mm).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm import tqdm

from mjcf import BuiltArm, MJCFOptions, build
from sim.playback import kinematic_playback
from sim.render import OffscreenRenderer
from zrp.errors import InputError, OutputExistsError, ZRPError
from zrp.kinematics.forward import check_q
from zrp.model.manipulator import Manipulator
from zrp.rotations import rotation_angle

__all__ = [
    "PAPER_LEVELS",
    "VideoOptions",
    "VideoResult",
    "VideoWriteError",
    "comparison_frames",
    "exaggerated_model",
    "nice_factor",
    "render_comparison_video",
    "render_paper_video",
    "render_teaching_sweep",
]

F64 = NDArray[np.float64]
FORMATS = ("auto", "mp4", "gif")
PAPER_LEVELS = (0.0, 0.02, 0.05, 0.07, 0.1)

DESIRED_RGBA = (0.25, 0.55, 1.0, 1.0)
ACTUAL_RGBA = (1.0, 0.25, 0.2, 1.0)
ARROW_RGBA = (1.0, 0.85, 0.1, 1.0)
GHOST_RGBA = (0.6, 0.9, 1.0, 1.0)


class VideoWriteError(ZRPError, OSError):
    """The video file cannot be written (the message names the path and the reason)."""


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
        azimuth, elevation: camera angles, deg.
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
    ghost_alpha: float = 0.4
    azimuth: float = 150.0
    elevation: float = -15.0
    plot: bool = True
    exaggerate_arm: bool = True

    def __post_init__(self) -> None:
        for name in ("width", "height", "fps", "trace_segments"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
                raise InputError(f"{name}: expected a positive integer, got {v!r}")
        if self.seconds is not None and not (math.isfinite(self.seconds) and self.seconds > 0):
            raise InputError(f"seconds: expected a positive duration (s) or None, got "
                             f"{self.seconds!r}")
        if self.magnify is not None and not (math.isfinite(self.magnify) and self.magnify > 0):
            raise InputError(f"magnify: expected a positive factor or None (auto), got "
                             f"{self.magnify!r}")
        if self.format not in FORMATS:
            raise InputError(f"format: unknown video format {self.format!r}; expected one of "
                             f"{FORMATS}")
        if not 0 < self.ghost_alpha <= 1:
            raise InputError(f"ghost_alpha: expected an opacity in (0, 1], got "
                             f"{self.ghost_alpha!r}")
        if self.backend is not None:
            from sim.gl import _check_name

            _check_name(self.backend, "backend")


@dataclass(frozen=True, eq=False)
class VideoResult:
    """What was written and what it shows.

    Attributes:
        path: the video file.
        frames: number of frames.
        wall_seconds: end-to-end time (models, playback, rendering, encoding), s.
        magnify: deviation magnification drawn.
        max_delta_p: largest delta_p per segment, model length unit.
        max_delta_r: largest eq-(15) delta_R per segment (dimensionless).
        max_theta: largest error-rotation angle per segment, rad.
        labels: segment labels.
        backend: GL backend used.
    """

    path: Path
    frames: int
    wall_seconds: float
    magnify: float
    max_delta_p: tuple[float, ...]
    max_delta_r: tuple[float, ...]
    max_theta: tuple[float, ...]
    labels: tuple[str, ...]
    backend: str
    length_unit: str = "mm"
    extra: dict[str, object] = field(default_factory=dict)

    def summary(self) -> str:
        rows = [f"{self.path}: {self.frames} frames in {self.wall_seconds:.1f} s "
                f"({self.frames / self.wall_seconds:.1f} frames/s end to end, {self.backend}), "
                f"deviations drawn x{self.magnify:g}"]
        for lab, dp, dr, th in zip(self.labels, self.max_delta_p, self.max_delta_r,
                                   self.max_theta, strict=False):
            lab = lab.replace("\n", "; ")
            rows.append(f"  {lab}: max delta_p {dp:.4g} {self.length_unit}, max delta_R (eq 15) "
                        f"{dr:.4g}, max theta {th:.4g} rad")
        return "\n".join(rows)


def exaggerated_model(nominal: Manipulator, perturbed: Manipulator, factor: float
                      ) -> Manipulator:
    """The perturbed model with its parameter errors multiplied by ``factor`` (for drawing).

    b_k = b_k,nom + F (b_k,pert - b_k,nom); axes u_k = normalise(u_k,nom + F (u_k,pert -
    u_k,nom)); the hand vectors likewise, u_t re-orthogonalised to u_a. To first order in the
    errors the tool point moves F times as far from the nominal one as the perturbed arm's.
    """
    f = float(factor)

    def mix(a: ArrayLike, b: ArrayLike) -> F64:
        return np.asarray(a, dtype=float) + f * (np.asarray(b, dtype=float) - np.asarray(a))

    axes = mix(nominal.axes, perturbed.axes)
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    ua = mix(nominal.end_effector.axial, perturbed.end_effector.axial)
    ua /= np.linalg.norm(ua)
    ut = mix(nominal.end_effector.transverse, perturbed.end_effector.transverse)
    ut -= (ut @ ua) * ua
    ut /= np.linalg.norm(ut)
    return perturbed.with_arrays(axes=axes, bodies=mix(nominal.bodies, perturbed.bodies),
                                 axial=ua, transverse=ut,
                                 name=f"{perturbed.name} (errors x{f:g})")


def nice_factor(x: float) -> float:
    """Largest 1, 2 or 5 times a power of ten not above ``x`` (x > 0); 1 for x <= 0."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    e = math.floor(math.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**e <= x:
            return m * 10**e
    return 10.0**e


# ---- output ------------------------------------------------------------------------------
def _check_output(path: Path, overwrite: bool) -> Path:
    """Refuse to replace ``path`` unless ``overwrite``; create its folder; return the temporary
    file the video is written to (renamed onto ``path`` only when complete)."""
    if path.exists() and not overwrite:
        raise OutputExistsError(f"output {str(path)!r} exists; pass overwrite=True (--force) "
                                f"to replace it")
    if path.is_dir():
        raise InputError(f"output {str(path)!r} is a directory; expected a video file path")
    part = path.with_name(f".{path.stem}.part{path.suffix}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(part, "wb"):
            pass
    except OSError as exc:
        raise VideoWriteError(f"output {str(path)!r}: cannot write ({exc.strerror or exc})") \
            from exc
    return part


def _ffmpeg_available() -> bool:
    try:
        import imageio_ffmpeg

        imageio_ffmpeg.get_ffmpeg_exe()
        return True
    except Exception:  # package missing or no binary
        return False


@contextmanager
def _writer(path: Path, fmt: str, width: int, height: int, fps: int
            ) -> Iterator[Callable[[NDArray[np.uint8]], None]]:
    if fmt == "mp4":
        import imageio_ffmpeg

        gen = imageio_ffmpeg.write_frames(str(path), (width, height), fps=fps, codec="libx264",
                                          pix_fmt_out="yuv420p", macro_block_size=2,
                                          output_params=["-preset", "veryfast", "-crf", "23"],
                                          ffmpeg_log_level="error")
        gen.send(None)
        try:
            yield lambda frame: gen.send(np.ascontiguousarray(frame))
        finally:
            gen.close()
    else:
        from PIL import Image

        frames: list[Image.Image] = []
        yield lambda frame: frames.append(Image.fromarray(frame).quantize(colors=128))
        if frames:
            frames[0].save(path, save_all=True, append_images=frames[1:],
                           duration=round(1000 / fps), loop=0)


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
    q = check_q(nominal, q)
    t = np.asarray(t, dtype=float)
    if q.ndim != 2 or t.shape != (q.shape[0],) or len(t) < 2:
        raise InputError(f"t, q: expected shapes (N,) and (N, {nominal.n}) with N >= 2, got "
                         f"{t.shape} and {q.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("t: expected finite, strictly increasing times (s)")
    tf = np.linspace(t[0], t[-1], frames)
    qf = np.stack([np.interp(tf, t, q[:, j]) for j in range(nominal.n)], axis=1)
    arm_a = build(perturbed, MJCFOptions(offscreen_size=size))
    arm_n = build(nominal, MJCFOptions(alpha=ghost_alpha, floor=False, prefix="ghost_",
                                       tint=GHOST_RGBA, offscreen_size=size))
    des = kinematic_playback(arm_n, qf)
    act = kinematic_playback(arm_a, qf)
    dp = np.linalg.norm(act.position - des.position, axis=-1)
    theta = rotation_angle(des.frame, act.frame)
    dr = 2.0 * math.sqrt(2.0) * np.sin(theta / 2.0)  # eq (15) = sqrt(4(1 - e0^2 + e.e))
    return _Segment(arm_n, arm_a, tf, qf, des.position * arm_n.scale,
                    act.position * arm_a.scale, dp, dr, theta, label)


def _camera(r: OffscreenRenderer, segs: Sequence[_Segment], opts: VideoOptions) -> None:
    """Frame the whole arm and the path: look between the base and the path's centre."""
    seg = segs[0]
    path_c = seg.p_des.mean(axis=0)
    bodies = np.asarray(seg.nominal.manipulator.bodies) * seg.nominal.scale
    reach = max(float(np.sum(np.linalg.norm(bodies, axis=1))), 0.2)
    centre = 0.5 * path_c
    r.look_at(centre, 1.5 * reach, opts.azimuth, opts.elevation)


def _segment_frames(r: OffscreenRenderer, seg: _Segment, magnify: float, opts: VideoOptions,
                    unit: str, title: str, plot_top: float | None = None
                    ) -> Iterator[NDArray[np.uint8]]:
    drawn = seg.drawn or seg.actual
    m_a, m_n = drawn.model, seg.nominal.model
    d_a, d_n = mujoco.MjData(m_a), mujoco.MjData(m_n)
    n_frames = len(seg.t)
    magnified = seg.p_des + magnify * (seg.p_act - seg.p_des)
    stride = max(1, math.ceil((n_frames - 1) / opts.trace_segments))
    idx_all = np.unique(np.r_[np.arange(0, n_frames, stride), n_frames - 1])
    path_size = float(np.linalg.norm(seg.p_des.max(axis=0) - seg.p_des.min(axis=0))) or 0.1
    arrow_r = 0.006 * max(path_size, 0.1)
    fig = mujoco.MjvFigure()
    if opts.plot:
        mujoco.mjv_defaultFigure(fig)
        fig.flg_extend = 0
        fig.flg_ticklabel[0] = 1
        fig.flg_ticklabel[1] = 1
        fig.gridsize[:] = [3, 3]
        fig.title = f"delta_p ({unit})"
        fig.xlabel = "t (s)"
        fig.range[0][:] = [seg.t[0], seg.t[-1]]
        top = plot_top if plot_top is not None else float(seg.delta_p.max())
        fig.range[1][:] = [0.0, 1.1 * (top or 1e-12)]
        fig.linergb[0][:] = ACTUAL_RGBA[:3]
        fig.figurergba[:] = [0.05, 0.05, 0.08, 0.85]
        fig.panergba[:] = [0.12, 0.12, 0.15, 1.0]
        fig.linewidth = 2.0
        fig.legendrgba[3] = 0.0
    max_pts = len(fig.linedata[0]) // 2 if opts.plot else 0
    plot_idx = np.linspace(0, n_frames - 1, min(n_frames, max_pts)).astype(int) if opts.plot \
        else np.zeros(0, int)
    pw, ph = int(opts.width * 0.36), int(opts.height * 0.27)
    legend = "blue: desired (nominal)\nred: actual (perturbed)\npale ghost: nominal arm"
    if seg.drawn is not None:
        legend += f"\narm: perturbed, errors x{magnify:g}"
    for f in range(n_frames):
        d_a.qpos[drawn.qpos_adr] = drawn.qpos(seg.q[f])
        d_n.qpos[seg.nominal.qpos_adr] = seg.nominal.qpos(seg.q[f])
        mujoco.mj_kinematics(m_a, d_a)
        mujoco.mj_kinematics(m_n, d_n)
        r.update_scene(d_a, [(m_n, d_n)], model=m_a)
        r.add_polyline(seg.p_des[idx_all], DESIRED_RGBA, 2.0)
        done = idx_all[idx_all <= f]
        if len(done) and done[-1] != f:
            done = np.r_[done, f]
        if len(done) > 1:
            r.add_polyline(magnified[done], ACTUAL_RGBA, 2.5)
        if np.linalg.norm(magnified[f] - seg.p_des[f]) > 1e-9:
            r.add_arrow(seg.p_des[f], magnified[f], ARROW_RGBA, arrow_r)
        r.render()
        r.text(f"{title}\n{seg.label}\ndeviations drawn x{magnify:g}",
               corner=mujoco.mjtGridPos.mjGRID_TOPLEFT)
        r.text("t\ndelta_p\ndelta_R (eq 15)\ntheta",
               f"{seg.t[f]:.2f} s\n{seg.delta_p[f]:.4g} {unit}\n{seg.delta_r[f]:.3e}\n"
               f"{seg.theta[f]:.3e} rad", corner=mujoco.mjtGridPos.mjGRID_BOTTOMLEFT)
        r.text(legend, corner=mujoco.mjtGridPos.mjGRID_TOPRIGHT)
        if opts.plot:
            shown = plot_idx[plot_idx <= f]
            fig.linepnt[0] = len(shown)
            if len(shown):
                fig.linedata[0][0:2 * len(shown):2] = seg.t[shown]
                fig.linedata[0][1:2 * len(shown):2] = seg.delta_p[shown]
            r.figure(fig, opts.width - pw - 4, 4, pw, ph)
        yield r.read()


def _prepare(segments_in: Sequence[tuple[Manipulator, Manipulator, ArrayLike, ArrayLike, str]],
             opts: VideoOptions) -> tuple[list[_Segment], float, float]:
    """Segments, the magnification and the common plot top (model unit)."""
    size = (max(opts.width, 640), max(opts.height, 480))
    segs = []
    for nominal, perturbed, t, q, label in segments_in:
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
        size = (max(opts.width, 640), max(opts.height, 480))
        drawn = []
        for s, (nominal, perturbed, *_rest) in zip(segs, segments_in, strict=True):
            try:
                shown = exaggerated_model(nominal, perturbed, magnify)
            except ZRPError:  # a degenerate exaggeration: draw the true arm
                shown = perturbed
            drawn.append(replace(s, drawn=build(shown, MJCFOptions(offscreen_size=size))))
        segs = drawn
    return segs, magnify, top


def _frames(segs: Sequence[_Segment], magnify: float, top: float, opts: VideoOptions,
            title: str, r: OffscreenRenderer) -> Iterator[NDArray[np.uint8]]:
    unit = segs[0].nominal.manipulator.length_unit
    _camera(r, segs, opts)
    for seg in segs:
        if (seg.drawn or seg.actual).model.nbody != r.model.nbody:
            raise InputError("segments: every perturbed model must have the same structure "
                             "as the first")
        yield from _segment_frames(r, seg, magnify, opts, unit, title, top)


def comparison_frames(
    nominal: Manipulator,
    perturbed: Manipulator,
    t: ArrayLike,
    q: ArrayLike,
    *,
    label: str = "",
    title: str = "nominal vs perturbed",
    options: VideoOptions | None = None,
) -> Iterator[NDArray[np.uint8]]:
    """The frames of :func:`render_comparison_video` without encoding, each shape
    (height, width, 3) uint8 (e.g. for ``mediapy.show_video`` in a notebook).

    The GL context is freed when the generator finishes or is closed; use
    ``contextlib.closing(comparison_frames(...))`` when stopping early.
    """
    opts = options or VideoOptions()
    segs, magnify, top = _prepare([(nominal, perturbed, t, q, label)], opts)
    with OffscreenRenderer((segs[0].drawn or segs[0].actual).model, opts.width, opts.height,
                           backend=opts.backend) as r:
        yield from _frames(segs, magnify, top, opts, title, r)


def _render(segments_in: Sequence[tuple[Manipulator, Manipulator, ArrayLike, ArrayLike, str]],
            out_path: str | Path, opts: VideoOptions, overwrite: bool, progress: bool,
            title: str) -> VideoResult:
    start = time.perf_counter()
    path = Path(out_path)
    fmt = opts.format
    if fmt == "auto":
        fmt = "mp4" if _ffmpeg_available() else "gif"
        if fmt == "gif" and path.suffix.lower() == ".mp4":
            path = path.with_suffix(".gif")
    segs, magnify, top = _prepare(segments_in, opts)
    unit = segs[0].nominal.manipulator.length_unit
    total = sum(len(s.t) for s in segs)
    part = _check_output(path, overwrite)
    try:
        with OffscreenRenderer((segs[0].drawn or segs[0].actual).model, opts.width,
                               opts.height, backend=opts.backend) as r:
            backend = r.backend
            with _writer(part, fmt, opts.width, opts.height, opts.fps) as write, \
                    tqdm(total=total, desc=f"render {path.name}", unit="frame",
                         disable=not progress) as bar:
                for frame in _frames(segs, magnify, top, opts, title, r):
                    write(frame)
                    bar.update(1)
        part.replace(path)
    except OSError as exc:
        raise VideoWriteError(f"output {str(path)!r}: cannot write ({exc})") from exc
    finally:
        part.unlink(missing_ok=True)
    return VideoResult(path, total, time.perf_counter() - start, magnify,
                       tuple(float(np.max(s.delta_p)) for s in segs),
                       tuple(float(np.max(s.delta_r)) for s in segs),
                       tuple(float(np.max(s.theta)) for s in segs),
                       tuple(s.label for s in segs), backend, unit)


def render_comparison_video(
    nominal: Manipulator,
    perturbed: Manipulator,
    t: ArrayLike,
    q: ArrayLike,
    out_path: str | Path,
    *,
    label: str = "",
    title: str = "nominal vs perturbed",
    options: VideoOptions | None = None,
    overwrite: bool = False,
    progress: bool = True,
) -> VideoResult:
    """Render the nominal (ghost) and perturbed arm following the joint trajectory ``q(t)``.

    Args:
        nominal, perturbed: ZRP models with the same joints.
        t: times, s, shape (N,); q: joint values, shape (N, n) (the nominal inverse kinematics).
        out_path: .mp4 or .gif path (becomes .gif when ffmpeg is missing and format="auto").
        label: perturbation text shown on the video.
        overwrite: replace an existing file.
    """
    opts = options or VideoOptions()
    return _render([(nominal, perturbed, t, q, label)], out_path, opts, overwrite, progress,
                   title)


def _perturbed_puma(parameter: str, xi_percent: float) -> tuple[Manipulator, Manipulator, str]:
    from zrp.manufacturing.perturb import Perturbation
    from zrp.model.files import load_model

    nominal = load_model("puma")
    pert = Perturbation.single(parameter, xi_percent)
    label = f"{parameter} xi = {xi_percent:+g} %\n{pert.convention}"
    return nominal, pert.apply(nominal), label


def render_paper_video(
    out_dir: str | Path = "renders",
    *,
    parameter: str = "JE2",
    xi_percent: float = 0.1,
    steps: int = 360,
    options: VideoOptions | None = None,
    overwrite: bool = True,
    progress: bool = True,
) -> VideoResult:
    """The paper's 125 mm PUMA circle: nominal ghost vs one perturbed parameter.

    Writes ``<out_dir>/puma_circle_<parameter>_<xi>.mp4`` (``renders/`` is generated output,
    replaced by default).
    """
    from zrp.paper.scenario import puma_circle_ik

    ik = puma_circle_ik(steps=steps)
    nominal, perturbed, label = _perturbed_puma(parameter, xi_percent)
    path = Path(out_dir) / f"puma_circle_{parameter}_{xi_percent:g}pct.mp4"
    return _render([(nominal, perturbed, ik.t, ik.q, label)], path, options or VideoOptions(),
                   overwrite, progress, "PUMA, 125 mm circle")


def render_teaching_sweep(
    out_dir: str | Path = "renders",
    *,
    parameter: str = "JE2",
    levels: Sequence[float] = PAPER_LEVELS,
    seconds_per_level: float = 3.0,
    steps: int = 360,
    options: VideoOptions | None = None,
    overwrite: bool = True,
    progress: bool = True,
) -> VideoResult:
    """Teaching demo: the PUMA circle at each of the paper's perturbation levels in turn,
    drawn at ONE magnification so the deviation visibly grows with xi.

    Writes ``<out_dir>/puma_sweep_<parameter>.mp4``.
    """
    from zrp.paper.scenario import puma_circle_ik

    if not levels:
        raise InputError("levels: expected at least one perturbation level (percent)")
    ik = puma_circle_ik(steps=steps)
    segs = []
    for xi in levels:
        nominal, perturbed, label = _perturbed_puma(parameter, float(xi))
        segs.append((nominal, perturbed, ik.t, ik.q, label))
    opts = replace(options or VideoOptions(), seconds=seconds_per_level)
    path = Path(out_dir) / f"puma_sweep_{parameter}.mp4"
    return _render(segs, path, opts, overwrite, progress,
                   f"PUMA circle: {parameter} swept over the paper's levels")
