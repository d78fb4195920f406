"""The comparison video's legend names only what the frame shows, and what it names is in
the frame's pixels: for every legend entry (green desired path, magenta actual path, yellow
arrow, orange arm, white ghost, purple earlier paths) its colour is present in the scene on
the frames whose legend names it and absent on the others, in the paper's video, the
teaching sweep (whose xi = 0 level draws the arm exactly on the ghost) and the nominal-only
video of notebook 2 (perturbed = nominal). The deviation arrow was hidden inside the wrist in
every frame when it was a 3D arrow; the nominal-only video named a perturbed arm and a
ghost it did not show; frame 0 named a magenta path of one point."""

from __future__ import annotations

import numpy as np
import pytest

import sim
import zrp
from sim.view.overlays import (
    ARROW_RGB_U8,
    MIN_ARROW_PX,
    MIN_PATH_PX,
    legend_text,
    paint_arrow,
    visible_in_frame,
)
from zrp.paper.scenes import paper_video_scene, teaching_sweep_scene

W, H = 640, 480


def _scene_px(img: np.ndarray) -> np.ndarray:
    """The scene: left of the right-hand column (legend, numbers, plot), below the titles."""
    return img[55:, : W - 260].astype(int)


def _yellow(img: np.ndarray) -> np.ndarray:
    return np.abs(img.astype(int) - np.array(ARROW_RGB_U8)).sum(axis=-1) <= 6


#: Each legend entry: the words that name it, and its colour in the scene's pixels (lines are
#: drawn unlit in their colour; the arm is lit orange; the ghost is a lit translucent white
#: that shows as a bright neutral grey, brighter than the arm's grey base; the earlier paths'
#: dim purple is told from magenta half-blended into black or into the ghost by its ratios).
ENTRIES = {
    "green": ("green:", lambda r, g, b: (g >= 150) & (r <= 120) & (b <= 150)),
    "magenta": ("magenta:", lambda r, g, b: (r >= 180) & (g <= 120) & (b >= 140)),
    "yellow": ("yellow arrow", lambda r, g, b: (np.abs(r - ARROW_RGB_U8[0]) + np.abs(
        g - ARROW_RGB_U8[1]) + np.abs(b - ARROW_RGB_U8[2])) <= 6),
    "orange": ("orange:", lambda r, g, b: (r >= 100) & (g >= 0.35 * r) & (g <= 0.75 * r)
               & (b <= 0.45 * r)),
    "ghost": ("white ghost", lambda r, g, b: (np.maximum(np.maximum(r, g), b)
                                              - np.minimum(np.minimum(r, g), b) <= 16)
              & (np.maximum(np.maximum(r, g), b) >= 150)),
    "purple": ("purple:", lambda r, g, b: (r >= 100) & (r <= 150) & (g >= 0.3 * r)
               & (g <= 0.5 * r) & (b >= 0.8 * r) & (b <= 1.0 * r)),
}


def _count(img: np.ndarray, name: str) -> int:
    im = _scene_px(img)
    return int(ENTRIES[name][1](im[..., 0], im[..., 1], im[..., 2]).sum())


def _mismatches(frames: list[np.ndarray], legends: list[str]) -> list[str]:
    """Frames where an entry's colour is present but the legend does not name it, or named
    but absent (pixel counts)."""
    assert len(frames) == len(legends)
    bad = []
    for i, (img, legend) in enumerate(zip(frames, legends, strict=True)):
        im = _scene_px(img)
        r, g, b = im[..., 0], im[..., 1], im[..., 2]
        for name, (words, colour) in ENTRIES.items():
            n = int(colour(r, g, b).sum())
            if (n > 0) != (words in legend):
                bad.append(f"frame {i}: {name} {n} px, legend {legend!r}")
    return bad


def _render(segments, magnify: float, fps: int, seconds: float, backend: str
            ) -> tuple[list[np.ndarray], list[str]]:
    opts = sim.VideoOptions(width=W, height=H, fps=fps, seconds=seconds, magnify=magnify,
                            backend=backend)
    legends: list[str] = []
    frames = list(sim.video_frames(segments, title="legend test", options=opts,
                                   legends=legends))
    return frames, legends


@pytest.fixture(scope="module")
def paper_video(backend):
    scene = paper_video_scene("JE2", 0.1, steps=60)
    return _render(scene.segments, scene.magnify, 10, 4.0, backend)


@pytest.fixture(scope="module")
def sweep_video(backend):
    scene = teaching_sweep_scene("JE2", (0.0, 0.05, 0.1), steps=60)
    return _render(scene.segments, scene.magnify, 5, 3.0, backend)


@pytest.fixture(scope="module")
def nominal_video(backend):
    """Notebook 2's left-hand video: the nominal model as both arms."""
    ik = zrp.puma_circle_ik(steps=60)
    model = zrp.load_model("puma")
    return _render([sim.VideoSegment(model, model, ik.t, ik.q, "nominal")], 100.0, 5, 4.0,
                   backend)


# ---- the rule -------------------------------------------------------------------------------
def _circle_px(n: int = 60, r: float = 50.0, c=(100.0, 100.0)) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, n)
    return np.stack([c[0] + r * np.cos(a), c[1] + r * np.sin(a)], axis=1)


def test_rule_paths_need_visible_length_and_are_hidden_under_lines_drawn_over_them():
    circle, still = _circle_px(), np.zeros((2, 2))
    body = np.array([[0.0, 0.0], [10.0, 0.0]])
    # a path of one point, or shorter than MIN_PATH_PX, is not visible
    for act in (circle[:1], np.array([[0.0, 0.0], [MIN_PATH_PX - 1.0, 0.0]])):
        assert not visible_in_frame(circle, act, [], still, body, body).actual
    # the actual path traced on the desired one: both visible while the rest of the desired
    # path shows, the desired one hidden when the whole circle is traced
    half = visible_in_frame(circle, circle[:30], [], still, body, body)
    assert half.desired and half.actual and half.on_desired
    full = visible_in_frame(circle, circle, [], still, body, body)
    assert not full.desired and full.actual and full.on_desired
    # moved off the desired path by 10 px: both visible, not "on the desired"
    off = visible_in_frame(circle, circle + np.array([10.0, 0.0]), [], still, body, body)
    assert off.desired and off.actual and not off.on_desired
    # an earlier path under the desired one is hidden; one beside it is visible
    ear = visible_in_frame(circle, circle[:1], [circle, circle * 1.2], still, body, body)
    assert ear.earlier == (False, True)
    # the tool's disk hides the part of a path inside it
    assert not visible_in_frame(circle, circle[:3], [], still, body, body,
                                (circle[2], 20.0)).actual


def test_rule_ghost_and_arrow():
    circle, body = _circle_px(), np.array([[0.0, 0.0], [10.0, 0.0]])
    same = visible_in_frame(circle, circle[:1], [], np.zeros((2, 2)), body, body + 0.5)
    assert not same.ghost and not same.arrow
    apart = visible_in_frame(circle, circle[:1], [], [[0, 0], [MIN_ARROW_PX, 0]], body,
                             body + np.array([0.0, 3.0]))
    assert apart.ghost and apart.arrow
    text = legend_text(100, True, same)
    assert "ghost" not in text and "perturbed = nominal" in text and "x100" not in text
    assert len(text.split("\n")) == len(legend_text(100, True, apart).split("\n"))
    assert "white ghost: nominal arm" in legend_text(100, True, apart)


def test_paint_arrow_paints_its_colour_and_skips_short_ones():
    img = np.zeros((50, 80, 3), np.uint8)
    assert not paint_arrow(img, (10, 10), (10 + MIN_ARROW_PX / 2, 10))
    assert not img.any()
    assert paint_arrow(img, (10, 25), (70, 25))
    ys, xs = np.nonzero(_yellow(img))
    assert xs.min() <= 10 and xs.max() >= 69 and ys.min() < 25 < ys.max()
    assert not paint_arrow(img, (5, 5), (5, float("nan")))   # no length: nothing


# ---- the frames -----------------------------------------------------------------------------
def test_paper_video_legend_matches_its_pixels(paper_video):
    frames, legends = paper_video
    assert _mismatches(frames, legends) == []
    # frame 0: the magenta path is one point, the deviation 0 (arm on the ghost)
    assert "magenta" not in legends[0] and "ghost" not in legends[0]
    named = ["yellow arrow" in leg for leg in legends]
    # the deviation is 0 at both ends of the circle and ~0.5 mm (x100 on screen) mid-way
    assert not named[0] and not named[-1] and sum(named) >= len(frames) // 3
    assert max(int(_yellow(f[:, : W - 260]).sum()) for f in frames) > 100
    assert all("white ghost" in leg for leg, n in zip(legends, named, strict=True) if n)


def test_sweep_legend_matches_its_pixels(sweep_video):
    frames, legends = sweep_video
    assert _mismatches(frames, legends) == []
    first = legends[:15]   # xi = 0: the arm on the ghost, the actual path on the desired one
    assert not any("white ghost" in leg or "yellow" in leg for leg in first)
    assert all("perturbed = nominal" in leg for leg in first)
    assert "magenta: actual = desired path" in first[-1] and "green" not in first[-1]
    # traced on the desired path, the actual one is drawn over it (the other way round the
    # green stayed whole, spotted with magenta): two thirds round, most of the circle is
    # magenta and little green is left (pixel counts; the circle at frame 0: all green)
    circle = _count(frames[0], "green")
    assert _count(frames[10], "green") < 0.5 * circle < _count(frames[10], "magenta")
    assert _count(frames[14], "magenta") >= 0.9 * circle
    assert not any("purple" in leg for leg in first)
    assert any("purple" in leg for leg in legends[15:])   # the earlier levels' paths


def test_nominal_only_video_names_no_perturbed_arm_or_ghost(nominal_video):
    frames, legends = nominal_video
    assert _mismatches(frames, legends) == []
    for leg in legends:
        assert "perturbed arm" not in leg and "ghost" not in leg and "yellow" not in leg
        assert "orange: arm (perturbed = nominal)" in leg


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
