"""Issue 13, the command line: every option is checked with a stated range before any work,
bad environments are named errors, and no user file is lost (exit code 2, one line, no
traceback)."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from zrp.cli import build_parser, main
from zrp.output import GENERATED_MARK

ROOT = Path(__file__).resolve().parents[2]


def _refused(capsys, argv: list[str], match: str) -> str:
    """Run ``zrp argv`` in-process: exit code 2 and ``match`` in the one-line error."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusal of an option value
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert match in err, err
    return err


def test_no_command_declares_an_unchecked_number():
    """Every numeric option goes through zrp.cli.options (a range), never bare int/float."""
    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    bare = [f"{name} {'/'.join(a.option_strings)}" for name, p in sub.choices.items()
            for a in p._actions if a.type in (int, float) and not a.choices]
    assert not bare, bare


@pytest.mark.parametrize("argv, match", [
    (["diagnose", "--model", "puma", "--data", "D", "--out", "o", "--seed", "-1"],
     "argument --seed: expected a whole number from 0"),
    (["tolerance", "--seed", "-1"], "argument --seed: expected a whole number from 0"),
    (["tolerance", "--length", "1e308"], "argument --length: expected a number in [0, 1e+09]"),
    (["tolerance", "--robots", "0"], "argument -n/--robots"),
    (["render", "--width", "100000"], "argument --width: expected a whole number from 16 to"),
    (["render", "--seconds", "1e9"], "argument --seconds: expected a number in (0, 600] s"),
    (["render", "--fps", "nan"], "argument --fps: expected a whole number"),
    (["ik", "--steps", "10000000"], "argument --steps: expected a whole number from 1 to 1000000"),
    (["ik", "--radius", "inf"], "argument --radius"),
    (["fk", "--q", "0", "0", "nan", "0", "0", "0"], "argument --q: expected a finite number"),
    (["diagnose", "--model", "puma", "--data", "D", "--out", "o", "--withheld", "0.99"],
     "argument --withheld: expected a number in (0, 0.5]"),
    (["gap-benchmark", "--workers", "0"], "argument --workers"),
    (["measure", "--out", "m.csv", "--poses", "-5"], "argument --poses"),
    (["study", "--xi", "1.5"], "argument --xi: expected a number in (-1, 1) %"),
])
def test_option_ranges(capsys, argv, match):
    _refused(capsys, argv, match)


@pytest.mark.parametrize("command", [
    ["render", "--steps", "20", "--seconds", "0.2", "--no-dynamics"],
    ["mjcf"],
    ["measure", "--poses", "10"],
])
def test_bogus_mujoco_gl_is_a_named_error(tmp_path, command):
    out = ["--out", str(tmp_path / "v")] if command[0] == "render" else \
        ["--out", str(tmp_path / ("m.xml" if command[0] == "mjcf" else "m.csv"))]
    proc = subprocess.run([sys.executable, "-m", "zrp", *command, *out], cwd=ROOT,
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MUJOCO_GL": "bogus"})
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "MUJOCO_GL environment variable: 'bogus'" in proc.stderr


def test_render_gif_writes_a_gif(tmp_path, capsys):
    assert main(["render", "--format", "gif", "--steps", "20", "--seconds", "0.2",
                 "--no-dynamics", "--no-progress", "--out", str(tmp_path)]) == 0
    assert [p.suffix for p in tmp_path.iterdir() if not p.name.startswith(".")] == [".gif"]


def test_render_keeps_an_existing_video(tmp_path, capsys):
    video = tmp_path / "puma_circle_JE2_0.1pct.gif"
    video.write_bytes(b"mine")
    _refused(capsys, ["render", "--format", "gif", "--steps", "20", "--seconds", "0.2",
                      "--no-dynamics", "--no-progress", "--out", str(tmp_path)], "--force")
    assert video.read_bytes() == b"mine"


@pytest.mark.parametrize("out, match", [
    ("afile", "exists and is not a folder"),
    ("/proc/x", "/proc/x: cannot create the folder"),
    ("afile/below", "afile is a file, not a folder"),
])
def test_diagnose_output_refused_before_the_work(tmp_path, capsys, measured_csv, out, match,
                                                 monkeypatch):
    (tmp_path / "afile").write_text("keep")
    import zrp.gap.pipeline as pipeline

    def never(*a, **k):
        raise AssertionError("the diagnosis ran before the output was refused")

    monkeypatch.setattr(pipeline, "run_diagnosis", never)
    target = out if out.startswith("/") else str(tmp_path / out)
    err = _refused(capsys, ["diagnose", "--model", "puma", "--data", str(measured_csv),
                            "--no-plots", "--out", target], "")
    assert match in err, err
    assert (tmp_path / "afile").read_text() == "keep"


def test_gap_benchmark_out_file(tmp_path, capsys):
    (tmp_path / "f").write_text("keep")
    _refused(capsys, ["gap-benchmark", "--out", str(tmp_path / "f"), "--scenarios", "1"],
             "exists and is not a folder")
    assert (tmp_path / "f").read_text() == "keep"


@pytest.mark.parametrize("name", ["h.txt", "fig"])
def test_tolerance_hist_must_be_png_and_keeps_fig_png(tmp_path, capsys, name):
    (tmp_path / "fig.png").write_text("keep")
    _refused(capsys, ["tolerance", "--robots", "100", "--steps", "40", "--no-progress",
                      "--hist", str(tmp_path / name)], "--hist:")
    assert (tmp_path / "fig.png").read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]


@pytest.mark.parametrize("out", ["renders", "renders/", "./renders"])
def test_a_users_renders_folder_is_kept(tmp_path, capsys, monkeypatch, out):
    """./renders that zrp did not make is the user's: its files are kept without --force,
    whichever way the folder is spelled; one zrp made (marked) is replaced."""
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "renders" / "puma_circle_joints.csv"
    table = tmp_path / "renders" / "comparison.md"
    mine.parent.mkdir()
    mine.write_text("mine")
    table.write_text("mine")
    _refused(capsys, ["ik", "--steps", "40"], "--force")
    _refused(capsys, ["paper", "--steps", "40", "--no-video", "--no-plots", "--out", out],
             "--force")
    assert mine.read_text() == "mine" and table.read_text() == "mine"


@pytest.mark.parametrize("exists", [False, True])
def test_a_renders_folder_zrp_made_is_replaced(tmp_path, capsys, monkeypatch, exists):
    """Missing or empty (as in a fresh clone): zrp makes it its own and replaces its files."""
    monkeypatch.chdir(tmp_path)
    if exists:
        (tmp_path / "renders").mkdir()
        (tmp_path / "renders" / ".gitkeep").write_text("")
    assert main(["ik", "--steps", "40"]) == 0
    assert (tmp_path / "renders" / GENERATED_MARK).is_file()
    assert main(["ik", "--steps", "40"]) == 0  # generated output: replaced
    capsys.readouterr()


def test_study_joints_in_degrees_refused(tmp_path, capsys):
    rows = ["t,q1,q2,q3,q4,q5,q6"] + [f"{t},0,10,20,30,90,0" for t in (0, 1, 2)]
    (tmp_path / "j.csv").write_text("\n".join(rows) + "\n")
    for cmd in (["study", "--params", "LE2", "--xi", "0.1"], ["tolerance", "--robots", "100",
                                                                "--no-progress"]):
        _refused(capsys, [*cmd, "--joints", str(tmp_path / "j.csv")],
                 "line 2: column q2 is 10, beyond 6.283 rad")


def test_diagnose_large_file_subsampled_with_notice(tmp_path, capsys, measured_csv):
    out = tmp_path / "o"
    assert main(["diagnose", "--model", "puma", "--data", str(measured_csv), "--max-steps", "1",
                 "--no-plots", "--max-points", "60", "--out", str(out)]) == 0
    doc = json.loads((out / "diagnosis.json").read_text())
    assert any("exceed max_points=60" in w for w in doc["warnings"])
    capsys.readouterr()


def test_diagnose_max_rows(tmp_path, capsys, measured_csv):
    _refused(capsys, ["diagnose", "--model", "puma", "--data", str(measured_csv), "--max-rows",
                      "10", "--out", str(tmp_path / "o")], "more than --max-rows=10")
    assert not (tmp_path / "o").exists()
