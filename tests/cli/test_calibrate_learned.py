"""``zrp calibrate --residual-model`` and ``zrp compensate`` with a learned residual term (issue
36): on a simulated IRB 120 whose tool points sag with a shape no effect of the library has
(zrp/gap/data/synthetic.py), the kept term is written into compensation.json and reported with
what it adds; ``zrp compensate`` refuses a program outside the term's training ranges, naming
the target and joint, and with --accept-flagged compensates it flagged."""

from __future__ import annotations

import contextlib
import io
import json
import re
import warnings

import numpy as np
import pytest

from zrp.cli import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.model.files import dumps_model

from ..calibration.pairs import write_bound
from ..gap.test_recovery import IRB120, LIMITS


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cal_learned")
    (folder / "irb120.toml").write_text(dumps_model(IRB120))
    rng = np.random.default_rng(11)
    q = uniform_joint_values(IRB120, 500, rng, LIMITS["irb120"])
    synthesize(IRB120, q, Injection(sag=0.15), rng=rng, noise_sigma=0.02).to_csv(
        folder / "data.csv")
    text = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stdout(text):
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", str(folder / "irb120.toml"), "--data",
                   str(folder / "data.csv"), "--out", str(folder / "cal"), "--no-progress",
                   "--residual-model"])
    assert rc == 0
    (folder / "stdout.txt").write_text(text.getvalue())
    return folder


def test_calibrate_writes_and_reports_the_kept_term(calibrated, capsys):
    doc = json.loads((calibrated / "cal" / "compensation.json").read_text())
    term = doc["learned_residual"]
    assert term["withheld_rms_hybrid"] < term["withheld_rms_physical"] == doc["withheld_rms"]
    assert "q2" in term["training_ranges"] and term["turn_axis"] == [0.0, 0.0, 1.0]
    diag = json.loads((calibrated / "cal" / "diagnosis.json").read_text())
    assert diag["residual_model"]["kept"] is True and diag["effects"]  # physics still named
    # the report: the physical effects named, and what the learned term adds
    text = (calibrated / "stdout.txt").read_text()
    assert f"(effects: {', '.join(diag['effects'])})" in text
    m = re.search(r"withheld RMS ([0-9.]+) mm \(physical model\) -> ([0-9.]+) mm with it", text)
    assert m and float(m.group(2)) == pytest.approx(term["withheld_rms_hybrid"], rel=1e-3)


def test_compensate_refuses_outside_the_training_ranges(calibrated, tmp_path, capsys):
    doc = json.loads((calibrated / "cal" / "compensation.json").read_text())
    (tmp_path / "calibrated.toml").write_text((calibrated / "cal" / "calibrated.toml")
                                              .read_text())
    lo, hi = doc["learned_residual"]["training_ranges"]["q2"]
    doc["learned_residual"]["training_ranges"]["q2"] = [lo, lo + 0.3 * (hi - lo)]
    write_bound(tmp_path / "compensation.json", doc)
    q = np.radians([[10.0, 0.0, 20.0, 5.0, 30.0, 0.0], [5.0, 0.0, 10.0, 0.0, 40.0, 0.0]])
    q[:, 1] = lo + 0.8 * (hi - lo)  # inside the measured range, outside the narrowed one
    prog = tmp_path / "program.csv"
    prog.write_text("target,q1,q2,q3,q4,q5,q6\n" + "".join(
        f"T{i + 1}," + ",".join(repr(float(v)) for v in row) + "\n" for i, row in enumerate(q)))
    argv = ["compensate", "--calibration", str(tmp_path / "compensation.json"), "--targets",
            str(prog), "--out", str(tmp_path / "cmd.csv")]
    capsys.readouterr()
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2 and "target T1: the command of joint 2" in err, err
    assert "learned residual term was trained on" in err and "--accept-flagged" in err
    rc = main([*argv, "--accept-flagged", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["outside_measured"] == 2


def test_calibrate_from_the_stored_diagnosis_says_the_term_is_not_there(calibrated, capsys):
    """diagnosis.json records that a learned term was kept but not the term: a calibration
    reusing it is the physical model alone, equal to the fresh one's physical part, and the
    summary says so instead of dropping the term silently."""
    out = calibrated / "reused"
    rc = main(["calibrate", "--model", str(calibrated / "irb120.toml"), "--data",
               str(calibrated / "data.csv"), "--out", str(out), "--no-progress",
               "--diagnosis", str(calibrated / "cal" / "diagnosis.json")])
    assert rc == 0
    said = capsys.readouterr().out
    assert "note: the stored diagnosis kept a learned residual term" in said
    assert "diagnosis.json does not hold it" in said
    fresh = json.loads((calibrated / "cal" / "compensation.json").read_text())
    reused = json.loads((out / "compensation.json").read_text())
    assert reused["learned_residual"] is None and fresh["learned_residual"] is not None
    for key in ("joint_map", "base_rotation", "base_translation", "tool_points",
                "joint_offsets_folded", "withheld_rms"):
        assert reused[key] == fresh[key], key
