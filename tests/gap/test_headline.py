"""The verdict an engineer reads in a minute (issue 33): a headline of at most 80 words with the
withheld error before -> after and the share removed, the effects that matter with their
joints, what remains and whether more data would help; then a small table, then the details in
their own sections, the same in the terminal, diagnosis.json, report.md and report.html."""

from __future__ import annotations

import html
import re
import warnings

import numpy as np
import pytest

import zrp
from zrp.gap import Injection, diagnose, synthesize, write_outputs
from zrp.gap.report import diagnosis_document, verdict_text
from zrp.gap.report.headline import MAX_WORDS, headline_text, summary_rows
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


@pytest.fixture(scope="module")
def synthetic():
    """A PUMA with a cyclic error on joint 2 and a play on joint 3, 0.02 noise."""
    rng = np.random.default_rng(1)
    q = uniform_joint_values(PUMA, 150, rng)
    meas = synthesize(PUMA, q, Injection(cyclic_error={2: (1, 6e-4, 0.0)}, backlash={3: 8e-4}),
                      rng=rng, noise_sigma=0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(PUMA, meas, seed=0)


def _first_paragraph(text: str) -> str:
    return text.strip().split("\n\n", 1)[0]


def _verdict_md(md: str) -> list[str]:
    """The blocks of report.md's verdict section (up to the next "## ")."""
    body = md.split("## Verdict\n", 1)[1].split("\n## ", 1)[0]
    return [b for b in body.strip().split("\n\n") if b.strip()]


def _check_headline(d, md: str, page: str) -> str:
    head = headline_text(d)
    assert len(head.split()) <= MAX_WORDS, head
    u = d.length_unit
    removed = 100 * (1 - d.final.rms / d.nominal.rms)
    assert head.startswith(f"Withheld error {d.nominal.rms:.3g} -> {d.final.rms:.3g} {u} RMS "
                           f"({removed:.0f} % removed"), head
    assert "What remains" in head
    # one headline everywhere: the terminal and diagnosis.json, report.md, report.html
    assert _first_paragraph(verdict_text(d)) == head
    assert _first_paragraph(diagnosis_document(d)["verdict"]) == head
    blocks = _verdict_md(md)
    assert blocks[0] == head and blocks[1].startswith("| withheld poses |")
    assert all(b.startswith("### ") for b in blocks[2::2])  # then the details, in sections
    box = re.search(r'<div id="verdict">(.*?)</div>', page, re.S)
    assert box is not None
    assert html.unescape(re.sub(r"<[^>]+>", "", box.group(1))).strip() == head
    assert "<table>" in page.split('id="verdict"', 1)[1].split("<h2>Data</h2>")[0]
    return head


def test_synthetic_headline_names_effects_joints_and_floor(synthetic, tmp_path):
    d = synthetic
    write_outputs(d, tmp_path, plots=False)
    head = _check_headline(d, (tmp_path / "report.md").read_text(encoding="utf-8"),
                           (tmp_path / "report.html").read_text(encoding="utf-8"))
    for effect in d.final_joints:
        assert effect in head
    assert "cyclic_error (joint 2" in head and "backlash (joint 3" in head
    assert not d.unexplained and "at the noise floor" in head
    # the table: after registration, the geometric calibration, the final model, the floor
    _, rows = summary_rows(d)
    assert [r[0].split(" (")[0] for r in rows] == [
        "after registration", "geometric calibration", "final model", "noise floor"]
    assert rows[2][1] == f"{d.final.rms:.4g}"


def test_real_irb120_headline_is_short_with_before_and_after(irb120_real, tmp_path):
    d = irb120_real.diagnosis
    write_outputs(d, tmp_path, plots=False)
    head = _check_headline(d, (tmp_path / "report.md").read_text(encoding="utf-8"),
                           (tmp_path / "report.html").read_text(encoding="utf-8"))
    assert f"geometric calibration alone {d.assessment.baseline.withheld.rms:.3g}" in head
    assert "noise floor" in head and d.unexplained
    # the details are all still there, below
    assert "conflict with the specified repeatability" in verdict_text(d)
