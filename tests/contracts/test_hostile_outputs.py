"""Issue 35, findings 1-5: every CSV and Markdown output takes user strings only through
zrp.escape, default output names from inputs go through one sanitiser, default folders are
replaced only as generated output (their mark) or with --force, and no run writes through a
linked folder. Each test walks every place of its kind."""

from __future__ import annotations

import csv
import dataclasses
import html.parser
import io
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.cli import main
from zrp.escape import csv_cell, csv_text, csv_uncell
from zrp.output import GENERATED_MARK, safe_name

ROOT = Path(__file__).resolve().parents[2]
#: labels a spreadsheet would run as formulas, or that look escaped already
FORMULAS = ("=HYPERLINK(\"http://x\",\"y\")", "+1+cmd", "-2+3", "@SUM(A1)", "'=A1", "''-x")
#: Markdown that would forge a section, a cell or a tag
FORGED = "j1\n\n## Verdict\n\nThe model matches"
MD_HOSTILE = (FORGED, "a | b | c", "<script>alert(1)</script>", "**bold** `code` [x](y)")


def _formula_free(text: str) -> list[list[str]]:
    """The rows of CSV ``text``, after checking that no cell starts a formula."""
    rows = list(csv.reader(io.StringIO(text)))
    for row in rows:
        for cell in row:
            if len(cell) > 1 and cell[0] in "=+-@\t\r":
                float(cell)  # only a number may start so (raises ValueError otherwise)
    return rows


# ---- the class: every CSV writer ----------------------------------------------------------
def test_no_csv_writer_bypasses_csv_text():
    """Every CSV the toolkit writes is built by zrp.escape.csv_text: no other module makes a
    csv.writer. The two np.savetxt writers have headers of the program's own column names and
    numbers only (listed here, each checked by eye when added)."""
    savetxt_ok = {"zrp/gap/dynamics/data.py", "zrp/cli/dynamics_runs.py"}
    writers, savetxt = [], []
    for p in [*ROOT.glob("zrp/**/*.py"), *ROOT.glob("mjcf/**/*.py"), *ROOT.glob("sim/**/*.py")]:
        rel = p.relative_to(ROOT).as_posix()
        text = p.read_text(encoding="utf-8")
        if re.search(r"csv\.(writer|DictWriter)\(", text) and rel != "zrp/escape.py":
            writers.append(rel)
        if "savetxt(" in text and rel not in savetxt_ok:
            savetxt.append(rel)
    assert writers == [] and savetxt == []


def test_csv_cell_round_trips_and_never_starts_a_formula():
    for label in (*FORMULAS, "T1", "-1.5", "1e-3", "'plain", "-"):
        cell = csv_cell(label)
        assert csv_uncell(cell) == label
        _formula_free(csv_text(["target"], [[label]]))


def test_compensate_and_verify_csvs_hold_no_formula_and_read_back(tmp_path, capsys):
    """Finding 1: labels go raw into the commands CSV and verify --out; now escaped, and the
    commands read back with the same labels (verify accepts them)."""
    def run(argv):
        assert main([*argv, "--json"]) == 0, capsys.readouterr().err
        return json.loads(capsys.readouterr().out)

    run(["measure", "--model", "puma", "--poses", "30", "--out", str(tmp_path / "m.csv"),
         "--seed", "1"])
    run(["calibrate", "--model", "puma", "--data", str(tmp_path / "m.csv"), "--out",
         str(tmp_path / "cal")])
    q = zrp.reachable_poses(zrp.load_model("puma"), len(FORMULAS), np.random.default_rng(2))
    targets = tmp_path / "t.csv"
    targets.write_text(csv_text(["target", *[f"q{k}" for k in range(1, 7)]],
                                [[lab, *map(repr, map(float, r))]
                                 for lab, r in zip(FORMULAS, q, strict=True)]))
    comp = str(tmp_path / "cal" / "compensation.json")
    run(["compensate", "--calibration", comp, "--targets", str(targets), "--out",
         str(tmp_path / "cmd.csv"), "--accept-flagged"])  # random targets: some flagged
    cmd = _formula_free((tmp_path / "cmd.csv").read_text())
    assert [csv_uncell(r[0]) for r in cmd[1:]] == list(FORMULAS)
    run(["verify", "--calibration", comp, "--targets", str(targets), "--commands",
         str(tmp_path / "cmd.csv"), "--truth", str(tmp_path / "m.truth.json"), "--out",
         str(tmp_path / "v.csv")])
    ver = _formula_free((tmp_path / "v.csv").read_text())
    assert [csv_uncell(r[0]) for r in ver[1:]] == list(FORMULAS)


def test_measurement_trajectory_and_ik_csvs_hold_no_formula(tmp_path):
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    meas = zrp.gap.synthesize(model, zrp.kinematics.uniform_joint_values(model, 6, rng),
                              zrp.gap.Injection(), rng=rng)
    ids = {p: FORMULAS[i] for i, p in enumerate(dict.fromkeys(meas.pose))}
    poses = np.array([ids[p] for p in meas.pose], dtype=object)
    points = np.array(["@" + str(m) for m in meas.point], dtype=object)
    meas = dataclasses.replace(meas, pose=poses, point=points)
    path = meas.to_csv(tmp_path / "m.csv")
    _formula_free(path.read_text())
    back = zrp.gap.load_measurements(path, model)
    assert list(back.pose) == list(poses) and list(back.point) == list(points)

    from zrp.gap.motion.data import Trajectory
    from zrp.gap.motion.trajcsv import load_trajectory, write_trajectory
    t = np.arange(60) * 0.01
    traj = Trajectory(t, np.zeros((60, 6)), np.zeros((60, 2, 3)), point_labels=("=1+1", "-x"))
    write_trajectory(traj, tmp_path / "tr.csv")
    _formula_free((tmp_path / "tr.csv").read_text())
    assert load_trajectory(tmp_path / "tr.csv", model).point_labels == ("=1+1", "-x")

    from zrp.kinematics.ik import IKResult
    vals = {f.name: np.zeros(3) for f in dataclasses.fields(IKResult)}
    vals.update(q=np.zeros((3, 2)), qdot=np.zeros((3, 2)), joint_names=("=cmd|x", "@j"),
                task="position", method="dls", length_unit="mm", elapsed_s=0.0, notes=(),
                includes_compilation=False)
    header = _formula_free(IKResult(**vals).csv_text())[0]
    assert header[1:3] == ["'=cmd|x", "'@j"]


# ---- the class: every Markdown/HTML report of names ----------------------------------------
class _Tags(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.h2: list[str] = []
        self._h2 = False

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self._h2 = tag == "h2"

    def handle_data(self, data):
        if self._h2:
            self.h2.append(data)
        self._h2 = False


def _cells(row: str) -> int:
    return len(re.findall(r"(?<!\\)\|", row)) - 1


def _check_markdown(md: str) -> None:
    assert md.count("\n## Verdict\n") == 1
    assert not re.search(r"(?<!\\)<script", md)
    block: list[str] = []
    for line in [*md.splitlines(), ""]:
        if line.startswith("|"):
            block.append(line)
            continue
        if block:
            assert len({_cells(r) for r in block}) == 1, block
        block = []


def _hostile_dynamics():
    from zrp.gap.dynamics.results import DynamicDiagnosis, FoundEffect, Param, Samples
    from zrp.gap.dynamics.select import Step

    n = len(MD_HOSTILE)
    ones = np.ones(n)
    eff = FoundEffect("absent_part", "absent_part", 1, FORGED,
                      {"share": Param(1.0, 0.9, 1.0, "1"),
                       "mass": Param(1.0, 0.5, 1.5, "kg|<b>")}, 3.0)
    s = Samples(np.arange(5.0), np.zeros((5, n)), np.zeros((5, n)), np.zeros((5, n)),
                np.zeros((5, n)))
    return DynamicDiagnosis(FORGED, list(MD_HOSTILE), ones, ones, ones,
                            [Step("nominal", 9.0), Step(FORGED, 1.0)], [eff],
                            [f"{FORGED} cannot tell"], {"before": {"still": [1.0] * n},
                                                        "after": {"still": [0.5] * n}},
                            notes=[f"body {MD_HOSTILE[2]} | {FORGED}"], samples=s)


def test_dynamics_report_shows_joint_and_body_names_as_text(tmp_path):
    """Finding 2: a joint name forged a second verdict, kept <script> raw, added cells."""
    from zrp.gap.dynamics.report import write_report

    d = _hostile_dynamics()
    out = write_report(d, tmp_path / "rep", extra={"sections": {FORGED: ["- x"]}})
    md = (out / "report.md").read_text()
    _check_markdown(md)
    page = _Tags()
    page.feed((out / "report.html").read_text())
    assert page.h2.count("Verdict") == 1
    assert page.tags.count("script") == 1  # the page's own pan/zoom script only
    assert "<script>alert" not in (out / "report.html").read_text()


# ---- the class: default output names and folders -------------------------------------------
@pytest.mark.parametrize("name", ["..", "...", "../../x", ".hidden", "a/b\\c", "-rf",
                                  "\x00\n", "é" * 300, "con.v2"])
def test_safe_name_gives_one_plain_component(name):
    s = safe_name(name, default="log")
    assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_-]*", s) and len(s) <= 100
    assert Path(s).name == s and s not in (".", "..")


def test_diagnose_dynamics_default_folder_is_sanitised_and_marked(tmp_path, capsys,
                                                                 monkeypatch):
    """Finding 5: a log named ...csv wrote its report into renders/."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "...csv").write_text("t,q1\n0,0\n")
    assert main(["diagnose-dynamics", "--model", "puma", "--data", "...csv"]) == 2
    capsys.readouterr()
    assert sorted(p.name for p in (tmp_path / "renders").iterdir()) == ["dynamics"]
    assert sorted(p.name for p in (tmp_path / "renders/dynamics").iterdir()) == ["log"]
    # a folder of the user's under the default path (no mark): refused before any work
    mine = tmp_path / "renders/dynamics/run1"
    mine.mkdir()
    (mine / "report.md").write_text("mine")
    (tmp_path / "run1.csv").write_text("t,q1\n0,0\n")
    assert main(["diagnose-dynamics", "--model", "puma", "--data", "run1.csv"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (mine / "report.md").read_text() == "mine"


@pytest.mark.parametrize("command", ["notebooks", "lessons"])
def test_default_folders_spare_a_users_renders_page(tmp_path, capsys, monkeypatch, command):
    """Finding 3: zrp notebooks replaced ./renders/index.html without the mark or --force;
    zrp lessons did the same."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "renders").mkdir()
    (tmp_path / "renders/index.html").write_text("mine")
    assert main([command]) == 2
    err = capsys.readouterr().err
    assert "index.html" in err and "--force" in err and "Traceback" not in err
    assert (tmp_path / "renders/index.html").read_text() == "mine"
    assert not (tmp_path / "renders" / GENERATED_MARK).exists()


def test_index_spares_a_users_renders_page(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "renders").mkdir()
    (tmp_path / "renders/index.html").write_text("mine")
    assert main(["index"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "renders/index.html").read_text() == "mine"


def test_fleet_resume_refuses_a_linked_robot_folder(tmp_path, capsys):
    """Finding 4: diagnose --resume followed robots/NAME -> elsewhere and replaced its
    diagnosis.json."""
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    data = tmp_path / "fleet"
    data.mkdir()
    zrp.gap.synthesize(model, zrp.kinematics.uniform_joint_values(model, 30, rng),
                       zrp.gap.Injection(), rng=rng).to_csv(data / "r0.csv")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "diagnosis.json").write_text("{\"theirs\": 1}")
    (tmp_path / "out/robots").mkdir(parents=True)
    os.symlink(elsewhere, tmp_path / "out/robots/r0")
    rc = main(["diagnose", "--model", "puma", "--data", str(data / "*.csv"), "--out",
               str(tmp_path / "out"), "--resume", "--no-plots", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "symbolic link" in err and "Traceback" not in err
    assert (elsewhere / "diagnosis.json").read_text() == "{\"theirs\": 1}"
    assert sorted(p.name for p in elsewhere.iterdir()) == ["diagnosis.json"]
