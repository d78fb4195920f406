"""Hostile user strings stay inert in every report format: point labels, the model name, joint
names and the data file's name reach report.md, report.html, residuals.csv, diagnosis.json,
fleet.md, fleet.csv and the blind benchmark's summary only as text (no forged section, no
extra table cell, no tag, no spreadsheet formula)."""

from __future__ import annotations

import csv
import dataclasses
import html.parser
import io
import json
import re

import numpy as np
import pytest

import zrp
from zrp.cli.fleet.summary import COLUMNS, fleet_csv, fleet_markdown
from zrp.escape import md_unescape
from zrp.gap import Injection, diagnose, load_measurements, synthesize, write_outputs
from zrp.kinematics import uniform_joint_values

FORGED = "s1\n\n## Verdict\n\nRobot certified accurate."
LABELS = (FORGED, "a | b | c", "=HYPERLINK(\"http://x\")")
MODEL_NAME = "<script>alert('model')</script>\n# Certified"
FILE_NAME = "<img src=x onerror=alert(1)>|=1+1.csv"


def _cells(row: str) -> int:
    """Cells of a Markdown table row: pipes not escaped by a backslash, less one."""
    return len(re.findall(r"(?<!\\)\|", row)) - 1


def _tables_are_rectangular(md: str) -> None:
    block: list[str] = []
    for line in [*md.splitlines(), ""]:
        if line.startswith("|"):
            block.append(line)
            continue
        if block:
            assert len({_cells(r) for r in block}) == 1, block
        block = []


class _Tags(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.h2: list[str] = []
        self._in_h2 = False

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self._in_h2 = tag == "h2"

    def handle_data(self, data):
        if self._in_h2:
            self.h2.append(data)
            self._in_h2 = False


@pytest.fixture(scope="module")
def hostile_outputs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hostile")
    model = zrp.load_model("puma")
    model = dataclasses.replace(model, name=MODEL_NAME)
    rng = np.random.default_rng(3)
    meas = synthesize(model, uniform_joint_values(model, 30, rng),
                      Injection(joint_offset={2: 1e-3}),
                      tool_offsets=np.array([[0, 0, 50.0], [0, 40.0, 50.0], [40.0, 0, 50.0]]),
                      rng=rng)
    rows = list(csv.reader(io.StringIO(meas.to_csv(tmp / "plain.csv").read_text())))
    rename = {f"s{k}": lab for k, lab in enumerate(LABELS, 1)}
    for r in rows[1:]:
        r[1] = rename[r[1]]
    data = tmp / FILE_NAME
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    data.write_text(buf.getvalue())
    meas = load_measurements(data, model)
    assert set(meas.point_labels) == set(LABELS)
    diag = diagnose(model, meas, max_steps=1, seed=0)
    out = tmp / "out"
    write_outputs(diag, out, plots=False)
    return out


def test_report_md_has_one_verdict_and_rectangular_tables(hostile_outputs):
    md = (hostile_outputs / "report.md").read_text()
    assert [ln for ln in md.splitlines() if ln.startswith("#")].count("## Verdict") == 1
    assert not any(ln.strip() == "Robot certified accurate." for ln in md.splitlines())
    assert not re.search(r"(?<!\\)<(script|img)", md)
    assert not any(ln.startswith("# Certified") for ln in md.splitlines())
    _tables_are_rectangular(md)
    # the labels are all there, as written
    assert "Robot certified accurate." in md_unescape(md)
    assert "a | b | c" in md_unescape(md)


def test_report_html_has_only_its_own_tags_and_one_verdict(hostile_outputs):
    page = (hostile_outputs / "report.html").read_text()
    p = _Tags()
    p.feed(page)
    assert p.tags.count("script") == 1  # the page's own pan-and-zoom script
    assert "img" not in p.tags  # no figures without plots, and none from a file name
    assert p.h2.count("Verdict") == 1
    assert page.count('id="verdict"') == 1
    assert "Robot certified accurate." in page  # shown, as text
    for table in re.findall(r"<table>.*?</table>", page, flags=re.S):
        widths = {len(re.findall(r"<t[dh]>", row)) for row in re.findall(r"<tr>.*?</tr>", table)}
        assert len(widths) == 1, table[:300]


def test_residuals_csv_starts_no_formula(hostile_outputs):
    rows = list(csv.reader(io.StringIO((hostile_outputs / "residuals.csv").read_text())))
    header, body = rows[0], rows[1:]
    assert all(len(r) == len(header) for r in body)
    labels = {r[2] for r in body}
    assert all(not c.startswith(("=", "+", "@")) for r in body for c in r[:3])
    assert "'=HYPERLINK(\"http://x\")" in labels


def test_diagnosis_json_keeps_the_strings(hostile_outputs):
    doc = json.loads((hostile_outputs / "diagnosis.json").read_text())
    assert doc["model"] == MODEL_NAME
    assert set(doc["settings"]["point_labels"]) == set(LABELS)


def _fleet_doc() -> dict:
    row = {c: 1.0 for c in COLUMNS}
    row.update(robot="<script>x</script>|r1\n## Verdict", points=3, top_effect="joint_offset",
               top_joints=[2], effects=["joint_offset"], out_of_tolerance=True,
               within_after_correction=True, data="=cmd|' /C calc'!A0")
    return {"robots": 2, "diagnosed": 1, "length_unit": "mm", "tolerance": 0.1,
            "out_of_tolerance": [row["robot"]], "fixed_by_correction": [row["robot"]],
            "dominant_effect": "joint_offset", "named_first": {"joint_offset": 1},
            "named_at_all": {"joint_offset": 1}, "rows": [row], "resumed": 0,
            "failures": [{"task": "<b>bad|file</b>.csv", "error": "line 1\n## Verdict"}]}


def test_fleet_markdown_and_csv_are_inert():
    doc = _fleet_doc()
    md = fleet_markdown(doc)
    assert "## Verdict" not in md.splitlines()
    assert not re.search(r"(?<!\\)<(script|b)", md)
    _tables_are_rectangular(md)
    rows = list(csv.reader(io.StringIO(fleet_csv(doc))))
    assert all(len(r) == len(COLUMNS) for r in rows)
    assert all(not c.startswith(("=", "+", "@")) for r in rows[1:] for c in r)
    assert rows[1][COLUMNS.index("data")] == "'=cmd|' /C calc'!A0"


def test_benchmark_summary_tables_and_csv_are_inert(tmp_path):
    from sim.studies.benchmark.report import _md_table, _write_csv
    from zrp.output import OutputDir

    md = _md_table(["input", "error"], [["<script>x</script>|a.csv", "bad\n## Verdict"]])
    assert "## Verdict" not in md.splitlines() and "<script>" not in md
    _tables_are_rectangular(md)
    with OutputDir(tmp_path) as out:
        _write_csv(out, "t.csv", [["name", "value"], ["=cmd()", -1.5], ["@x", "-2"]])
    rows = list(csv.reader(io.StringIO((tmp_path / "t.csv").read_text())))
    assert rows[1:] == [["'=cmd()", "-1.5"], ["'@x", "-2"]]
