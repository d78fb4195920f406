"""``zrp render``: the paper video, consistency numbers and dynamic playback from the CLI."""

from __future__ import annotations

import json

import pytest

import sim
from zrp.cli.app import main


@pytest.fixture(scope="module")
def backend() -> str:
    try:
        return sim.resolve_backend()
    except sim.GLUnavailableError as exc:
        pytest.skip(f"no offscreen GL backend: {exc}")


def test_render_command_writes_video_and_reports(backend, tmp_path, capsys):
    code = main(["render", "--out", str(tmp_path), "--width", "160", "--height", "120",
                 "--fps", "10", "--seconds", "0.3", "--steps", "60", "--no-progress", "--json",
                 "--backend", backend])
    assert code == 0
    payload = json.loads(capsys.readouterr().out)
    video = payload["videos"][0]
    assert video["frames"] == 3
    assert (tmp_path / "puma_circle_JE2_0.1pct.mp4").exists()
    assert all(c["passed"] for c in payload["consistency"])
    assert payload["dynamic_playback"]["max_tracking_error_mm"] > 0


def test_render_unknown_backend(tmp_path, capsys):
    assert main(["render", "--out", str(tmp_path), "--backend", "vulkan", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "vulkan" in err and "egl" in err and "osmesa" in err


def test_paper_video_bar_shows_the_file_the_user_gets(backend, tmp_path, capsys, monkeypatch):
    """``zrp paper`` renders its video into a temporary file moved into place afterwards; the
    progress bar showed that file (".zrp-PID-N.tmp.mp4", issue 33), now the final name."""
    from argparse import Namespace

    from zrp.cli.commands import paper
    from zrp.cli.commands.paper import _video, _video_name
    from zrp.model.files import load_model
    from zrp.output import OutputDir

    model = load_model("puma")
    args = Namespace(no_video=False, steps=40, json=False, progress=True)
    # the bar is drawn on a terminal only (zrp.cli.options.draw_bar); captured stderr is not one
    monkeypatch.setattr(paper, "draw_bar", lambda a: a.progress)
    name = _video_name(args, model)
    with OutputDir(tmp_path, names=[name]) as out:
        res = _video(args, out, name, model, "default")
    assert res == {"status": "written", "path": str(tmp_path / name)}
    bar = capsys.readouterr().err
    assert f"render {name}:" in bar
    assert ".zrp-" not in bar and ".tmp" not in bar, bar[-300:]
