"""Teaching outputs: videos framed on the circle (a frame of each video checked), the figures'
styles, the lessons (run at reduced size), the renders/ index (every output linked, no broken
link) and `zrp view` without a display."""

from __future__ import annotations

import html.parser
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sim
from zrp.output import OutputDir
from zrp.paper.figures import coincident_with
from zrp.paper.index import index_entries, write_index
from zrp.paper.scenes import paper_video_scene, teaching_sweep_scene

ROOT = Path(__file__).resolve().parents[2]


def _last_frame(path: Path) -> np.ndarray:
    import imageio_ffmpeg

    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    w, h = meta["size"]
    last = None
    for raw in gen:
        last = raw
    assert last is not None
    return np.frombuffer(last, dtype=np.uint8).reshape(h, w, 3)


def _bbox(mask: np.ndarray) -> tuple[int, int, int, int]:
    rows, cols = np.nonzero(mask)
    return int(rows.min()), int(rows.max()), int(cols.min()), int(cols.max())


@pytest.mark.parametrize("which", ["paper", "sweep"])
def test_video_frame_is_framed_on_the_circle(backend, tmp_path, which):
    scene = (paper_video_scene("JE2", 0.1, steps=120) if which == "paper"
             else teaching_sweep_scene("JE2", (0.05, 0.1), steps=120))
    opts = sim.VideoOptions(width=640, height=480, fps=20, seconds=2.0, format="mp4",
                            magnify=scene.magnify, backend=backend)
    res = sim.render_video(scene.segments, tmp_path / scene.file_name, title=scene.title,
                           options=opts, progress=False)
    fr = res.extra["framing"]
    assert abs(fr["circle_aspect"] - 1.0) < 0.1          # projected through MuJoCo's camera
    assert fr["arm_height_fraction"] >= 0.4
    img = _last_frame(res.path).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    # the desired path is the only saturated green on the frame (sim.view.overlays.DESIRED_RGBA)
    green = (g > 150) & (r < 120) & (b < 140)
    assert green.sum() > 100
    top, bottom, left, right = _bbox(green)
    aspect = (right - left + 1) / (bottom - top + 1)
    assert abs(aspect - 1.0) < 0.1, aspect                 # the circle looks round
    # the perturbed arm is the warm (orange/tan) object; the sweep keeps one magnification
    warm = (r > 120) & (r > g + 15) & (g > b + 15)
    t2, b2, _, _ = _bbox(warm)
    assert (b2 - t2 + 1) / img.shape[0] >= 0.4
    assert res.magnify == scene.magnify
    if which == "sweep":
        assert len(res.labels) == 2


def test_one_magnification_per_parameter():
    a = paper_video_scene("JE2", 0.05, steps=60)
    b = teaching_sweep_scene("JE2", steps=60)
    assert a.magnify == b.magnify and a.magnify > 0
    assert sim.nice_factor(a.magnify) == a.magnify


def test_noise_floor_prints_zero():
    from sim.view.overlays import NOISE_FLOOR, shown_value

    assert shown_value(1.59e-19, ".3e") == "0"
    assert shown_value(2 * NOISE_FLOOR, ".3e") == f"{2 * NOISE_FLOOR:.3e}"


def test_coincident_series_are_named():
    base = np.linspace(0, 1, 9)
    data = np.stack([base, 3 * base, base * 1.004, base + 0.5])
    assert coincident_with(data, ["JE1", "JE2", "JE4", "JE6"]) == {"JE4": "JE1"}


@pytest.fixture(scope="module")
def lesson_run(tmp_path_factory, backend):
    from sim.lessons import run_lessons

    out = tmp_path_factory.mktemp("renders") / "lessons"
    with OutputDir(out, names=[]) as folder:
        lessons = run_lessons(folder, small=True)
    return out, lessons


def test_lessons_run_and_teach_what_they_say(lesson_run):
    out, lessons = lesson_run
    by = {les.name: les for les in lessons}
    assert list(by) == ["tilt", "links", "stack", "backlash"]
    for les in lessons:
        for f in les.files:
            assert f.is_file() and f.stat().st_size > 1000, f
            assert f.parent == out
            assert len(les.sentences[f.name].split()) > 8
    # lesson 1: the measured error angle is the closed form 2 |sin(q2 / 2)| alpha
    assert by["tilt"].numbers["closed_form_rel_error"] < 1e-4
    # lesson 2: a link error turns the tool by exactly 0 and moves it by xi ||b3||
    assert by["links"].numbers["le3_max_angle_rad"] == 0.0
    assert by["links"].numbers["le3_delta_p_mm"] == pytest.approx(0.4318, rel=1e-9)
    # lesson 3: a distribution, well below the sum of the tolerances
    st = by["stack"].numbers
    assert 0 < st["p50_mm"] < st["p99_mm"] <= st["max_mm"]
    # lesson 4: the hidden backlash is named first, on its joint
    assert by["backlash"].numbers["found_first"] == "backlash on joint(s) [2]"
    assert by["backlash"].numbers["rms_final_mm"] < 0.5 * by["backlash"].numbers[
        "rms_nominal_mm"]


class _Links(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.hrefs: list[str] = []
        self.media: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "a":
            self.hrefs.append(a["href"])
        if tag in ("img", "video"):
            self.media.append(a["src"])


def test_index_links_every_output_and_no_link_is_broken(lesson_run):
    import json

    from zrp.jsonio import dumps

    out, lessons = lesson_run
    root = out.parent
    (out / "descriptions.json").write_text(
        dumps({k: v for les in lessons for k, v in les.sentences.items()}))
    import zrp

    zrp.write_paper_outputs(zrp.run_paper_example(steps=60), root / "paper", figures=True)
    page = write_index(root)
    parser = _Links()
    parser.feed(page.read_text(encoding="utf-8"))
    for href in parser.hrefs + parser.media:
        assert (root / href).is_file(), href
    files = {p.relative_to(root).as_posix() for p in root.rglob("*")
             if p.is_file() and not p.name.startswith(".")} - {"index.html",
                                                                "lessons/descriptions.json"}
    assert set(parser.hrefs) == files
    sentences = dict(index_entries(root))
    for les in lessons:
        for f in les.files:
            assert sentences[f"lessons/{f.name}"] == les.sentences[f.name]
    assert "no description" not in json.dumps(sentences)


def test_view_without_a_display_says_so():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    p = subprocess.run([sys.executable, "-m", "zrp", "view"], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert "no display" in p.stderr and "zrp render" in p.stderr
    assert "Traceback" not in p.stderr


def test_figures_keep_every_series_visible(tmp_path, monkeypatch):
    """Each figure as drawn: the legend lies outside the axes (it covers no data), every
    series of ours has its own (colour, dash, marker), series that coincide are named, and the
    eq (15) figures carry the plain error angle on a twin axis."""
    import zrp

    seen: dict[str, object] = {}
    original = OutputDir.savefig

    def record(self, name, fig, **kw):
        fig.canvas.draw()
        seen[name] = fig
        return original(self, name, fig, **kw)

    monkeypatch.setattr(OutputDir, "savefig", record)
    ex = zrp.run_paper_example(steps=60)
    with monkeypatch.context() as m:
        m.setattr("matplotlib.pyplot.close", lambda fig=None: None)
        zrp.write_paper_outputs(ex, tmp_path / "p")
    assert "fig3_je_max_rotation.png" in seen and "fig6_je_rotation_time_recovered.png" in seen
    for name, fig in seen.items():
        ax = fig.axes[0]
        box = ax.get_window_extent()
        leg = ax.get_legend().get_window_extent()
        assert leg.x0 >= box.x1 - 1, name                      # legend right of the axes
        ours = [ln for ln in ax.get_lines() if "published" not in ln.get_label()]
        styles = {(ln.get_color(), str(ln.get_linestyle()), ln.get_marker()) for ln in ours}
        assert len(styles) == len(ours), name
        labels = [ln.get_label() for ln in ours]
        if name.startswith(("fig3", "fig6")):
            assert any("mrad" in a.get_ylabel() for a in ax.child_axes), name
        if name == "fig3_je_max_rotation.png":     # JE4 within 0.5 % of JE1 on our circle
            assert any("(= JE1 within 1 %)" in lab for lab in labels), labels
        if name.startswith(("fig4", "fig7")):
            assert any("(= LE3 within 1 %)" in lab for lab in labels), labels
