"""The comparison video's legend names only what the frame shows: the yellow deviation arrow
is in the frame's pixels exactly on the frames whose legend names it (it was hidden inside the
wrist of both arms in every frame when it was a 3D arrow)."""

from __future__ import annotations

import numpy as np

import sim
from sim.view.overlays import ARROW_RGB_U8, MIN_ARROW_PX, legend_text, paint_arrow
from zrp.paper.scenes import paper_video_scene

W, H = 640, 480


def _yellow(img: np.ndarray) -> np.ndarray:
    return np.abs(img.astype(int) - np.array(ARROW_RGB_U8)).sum(axis=-1) <= 6


def _text_rows(img: np.ndarray) -> list[tuple[int, int]]:
    """Row bands (first, last) of the legend's text lines in the top right corner."""
    col = img[: H // 3, W - 250:].astype(int)
    on = (col.min(axis=-1) > 150).any(axis=1)   # white text pixels in the row
    bands, start = [], None
    for y, v in enumerate(on):
        if v and start is None:
            start = y
        if not v and start is not None:
            bands.append((start, y - 1))
            start = None
    return bands


def test_legend_text_names_the_arrow_only_when_painted():
    assert "yellow arrow: deviation x100" in legend_text(100, True, True)
    no = legend_text(100, True, False)
    assert "arrow" not in no and len(no.split("\n")) == 5   # same layout, blank line


def test_paint_arrow_paints_its_colour_and_skips_short_ones():
    img = np.zeros((50, 80, 3), np.uint8)
    assert not paint_arrow(img, (10, 10), (10 + MIN_ARROW_PX / 2, 10))
    assert not img.any()
    assert paint_arrow(img, (10, 25), (70, 25))
    ys, xs = np.nonzero(_yellow(img))
    assert xs.min() <= 10 and xs.max() >= 69 and ys.min() < 25 < ys.max()
    assert not paint_arrow(img, (5, 5), (5, float("nan")))   # no length: nothing


def test_frames_show_the_arrow_exactly_when_the_legend_names_it(backend):
    scene = paper_video_scene("JE2", 0.1, steps=60)
    opts = sim.VideoOptions(width=W, height=H, fps=10, seconds=4.0, magnify=scene.magnify,
                            backend=backend)
    frames = list(sim.video_frames(scene.segments, title="legend test", options=opts))
    scene_px = [int(_yellow(f[:, : W - 260]).sum()) for f in frames]
    bands = [len(_text_rows(f)) for f in frames]
    shown = [n > 0 for n in scene_px]
    # the deviation is 0 at both ends of the circle and ~0.5 mm (x100 on screen) mid-way
    assert not shown[0] and not shown[-1]
    assert sum(shown) >= len(frames) // 3, scene_px
    assert max(scene_px) > 100
    # five legend lines with the arrow, four without (the arrow's line left blank)
    assert set(bands) <= {4, 5}, bands
    assert [b == 5 for b in bands] == shown


def test_the_encoded_video_shows_the_arrow(backend, tmp_path):
    """Through libx264 (yuv420p) the arrow's yellow survives: present mid-circle, absent at
    the start where the deviation is 0 (colour within 60 of the painted one, summed over
    RGB)."""
    import imageio.v3 as iio

    scene = paper_video_scene("JE2", 0.1, steps=60)
    opts = sim.VideoOptions(width=W, height=H, fps=10, seconds=4.0, magnify=scene.magnify,
                            backend=backend, format="mp4")
    res = sim.render_video(scene.segments, tmp_path / "v.mp4", options=opts, progress=False)
    frames = iio.imread(res.path, plugin="FFMPEG", index=None)
    near = [int((np.abs(f[:, : W - 260].astype(int) - np.array(ARROW_RGB_U8)).sum(-1)
                 <= 60).sum()) for f in frames]
    assert near[0] == 0 and near[len(frames) // 2] > 50, near
