"""Comparison videos: the frames of :mod:`sim.view.frames` encoded into an mp4 or a gif file.

mp4: H.264 (libx264, ``-preset veryfast -crf 23``, yuv420p) piped to the ffmpeg binary that
:mod:`imageio_ffmpeg` ships; gif: Pillow (the fallback when ffmpeg is missing and
``format="auto"``). Every video is written under a temporary name beside its path and moved
into place when complete (:func:`zrp.output.atomic_path`); an existing file is replaced only
with ``overwrite=True``, and that is checked before any model is built or frame rendered.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from tqdm import tqdm

from sim.view.frames import VideoOptions, VideoSegment, _arm_points, _frames, _prepare
from sim.view.framing import framing_report
from sim.view.render import OffscreenRenderer
from zrp.arrays import U8
from zrp.errors import InputError, ZRPError
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path, check_writable

__all__ = [
    "VideoResult",
    "VideoWriteError",
    "render_comparison_video",
    "render_video",
    "video_path",
]



class VideoWriteError(ZRPError, OSError):
    """The video file cannot be written (the message names the path and the reason)."""


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
        fr = self.extra.get("framing")
        if isinstance(fr, dict):
            rows.append(f"  framing: circle aspect {fr['circle_aspect']:.3f}, arm "
                        f"{fr['arm_height_fraction']:.0%} of the frame height")
        for lab, dp, dr, th in zip(self.labels, self.max_delta_p, self.max_delta_r,
                                   self.max_theta, strict=False):
            lab = lab.replace("\n", "; ")
            rows.append(f"  {lab}: max delta_p {dp:.4g} {self.length_unit}, max delta_R (eq 15) "
                        f"{dr:.4g}, max theta {th:.4g} rad")
        return "\n".join(rows)


# ---- the file --------------------------------------------------------------------------------
@functools.cache
def _ffmpeg() -> str | None:
    """imageio-ffmpeg's ffmpeg binary, or None when the package or its binary is missing."""
    try:
        import imageio_ffmpeg

        return str(imageio_ffmpeg.get_ffmpeg_exe())
    except Exception:  # package missing or no binary
        return None


def _format(out_path: str | os.PathLike[str], fmt: str) -> tuple[Path, str]:
    """The file and the format it is written in: "auto" is mp4 when ffmpeg is available, else
    gif (and a ``.mp4`` name then becomes ``.gif``)."""
    path = Path(out_path)
    if fmt == "auto":
        fmt = "mp4" if _ffmpeg() else "gif"
    suffix = path.suffix.lower()
    if suffix in ("", ".mp4", ".gif") and suffix != f".{fmt}":
        path = path.with_suffix(f".{fmt}")  # the name follows the format asked for
    elif suffix != f".{fmt}":
        raise InputError(f"out_path: {str(path)!r} ends in {path.suffix!r}; a {fmt} video is "
                         f"written to a .{fmt} file")
    return path, fmt


def video_path(out_path: str | os.PathLike[str], options: VideoOptions | None = None) -> Path:
    """The file :func:`render_video` writes for ``out_path`` (a ``.mp4`` becomes ``.gif`` when
    ``format="auto"`` and ffmpeg is missing): check or reserve it before rendering."""
    return _format(out_path, (options or VideoOptions()).format)[0]


def _check_output(path: Path, overwrite: bool) -> None:
    """Refuse an existing file (unless ``overwrite``) or a path that cannot be a file."""
    try:
        check_writable([path], overwrite)
    except InputError as exc:
        raise VideoWriteError(f"output {str(path)!r}: cannot write ({exc})") from exc


@contextmanager
def _mp4_writer(path: Path, width: int, height: int, fps: int
                ) -> Iterator[Callable[[U8], None]]:
    # imageio-ffmpeg's own pipe writer, not mediapy.VideoWriter: the same ffmpeg command and
    # encoding time, but importing mediapy costs ~0.9 s (IPython, Matplotlib); see sim/README.md.
    import imageio_ffmpeg

    if _ffmpeg() is None:
        raise VideoWriteError(f"output {str(path)!r}: mp4 needs the ffmpeg of imageio-ffmpeg "
                              "(pip install imageio-ffmpeg); or use format='gif'")
    gen = imageio_ffmpeg.write_frames(str(path), (width, height), fps=fps, codec="libx264",
                                      pix_fmt_out="yuv420p", macro_block_size=2,
                                      output_params=["-preset", "veryfast", "-crf", "23"],
                                      ffmpeg_log_level="error")
    gen.send(None)
    try:
        yield lambda frame: gen.send(np.ascontiguousarray(frame))
    finally:
        gen.close()


@contextmanager
def _gif_writer(path: Path, fps: int) -> Iterator[Callable[[U8], None]]:
    from PIL import Image

    frames: list[Image.Image] = []
    yield lambda frame: frames.append(Image.fromarray(frame).quantize(colors=128))
    if frames:
        frames[0].save(path, save_all=True, append_images=frames[1:],
                       duration=round(1000 / fps), loop=0)


# ---- rendering ---------------------------------------------------------------------------------
def render_video(
    segments: Sequence[VideoSegment | tuple[Manipulator, Manipulator, ArrayLike, ArrayLike, str]],
    out_path: str | os.PathLike[str],
    *,
    title: str = "nominal vs perturbed",
    options: VideoOptions | None = None,
    overwrite: bool = False,
    progress: bool = True,
    progress_name: str | None = None,
) -> VideoResult:
    """Render segments one after the other into one video, at ONE magnification and one plot
    scale (so a deviation that grows from segment to segment visibly grows).

    Args:
        segments: :class:`sim.view.frames.VideoSegment` (nominal, perturbed, t, q, label) each; the
            perturbed models must share the first one's structure.
        out_path: .mp4 or .gif path (becomes .gif when ffmpeg is missing and format="auto";
            :func:`video_path` tells which).
        title: first line of the text on every frame.
        options: size, frame rate, length per segment, magnification, format, GL backend.
        overwrite: replace an existing file.
        progress: tqdm bar over the frames.
        progress_name: the file name the bar shows (default: ``out_path``'s own); give the
            final name when ``out_path`` is a temporary file that is moved onto it afterwards
            (:meth:`zrp.output.OutputDir.path`).
    """
    start = time.perf_counter()
    opts = options or VideoOptions()
    path, fmt = _format(out_path, opts.format)
    _check_output(path, overwrite)  # before the models are built and played back
    prep = _prepare(segments, opts)
    segs = prep.segments
    try:
        with OffscreenRenderer(prep.first_model, opts.width, opts.height,
                               backend=opts.backend) as r, \
                atomic_path(path, overwrite=overwrite) as tmp:
            backend = r.backend
            writer = (_mp4_writer(tmp, opts.width, opts.height, opts.fps) if fmt == "mp4"
                      else _gif_writer(tmp, opts.fps))
            bar = tqdm(total=prep.frames, desc=f"render {progress_name or path.name}",
                       unit="frame", disable=not progress)
            with writer as write, bar:
                for frame in _frames(prep, opts, title, r):
                    write(frame)
                    bar.update(1)
            framing = framing_report(r.scene, np.vstack([s.p_des for s in segs]),
                                     np.concatenate([_arm_points(s) for s in segs]),
                                     opts.width, opts.height)
    except InputError as exc:  # from atomic_path: the file could not be written or moved
        cause = exc.__cause__
        if isinstance(cause, VideoWriteError):
            raise cause from None
        if isinstance(cause, OSError):
            raise VideoWriteError(f"output {str(path)!r}: cannot write ({cause})") from cause
        raise
    return VideoResult(path, prep.frames, time.perf_counter() - start, prep.magnify,
                       tuple(float(np.max(s.delta_p)) for s in segs),
                       tuple(float(np.max(s.delta_r)) for s in segs),
                       tuple(float(np.max(s.theta)) for s in segs),
                       tuple(s.label for s in segs), backend,
                       segs[0].nominal.manipulator.length_unit, {"framing": framing})


def render_comparison_video(
    nominal: Manipulator,
    perturbed: Manipulator,
    t: ArrayLike,
    q: ArrayLike,
    out_path: str | os.PathLike[str],
    *,
    label: str = "",
    title: str = "nominal vs perturbed",
    options: VideoOptions | None = None,
    overwrite: bool = False,
    progress: bool = True,
) -> VideoResult:
    """Render the nominal (ghost) and perturbed arm following the joint trajectory ``q(t)``:
    :func:`render_video` of one segment.

    Args:
        nominal, perturbed: ZRP models with the same joints.
        t: times, s, shape (N,); q: joint values, shape (N, n) (the nominal inverse kinematics).
        out_path: .mp4 or .gif path (becomes .gif when ffmpeg is missing and format="auto").
        label: perturbation text shown on the video.
        overwrite: replace an existing file.
    """
    return render_video([VideoSegment(nominal, perturbed, t, q, label)], out_path, title=title,
                        options=options, overwrite=overwrite, progress=progress)
