"""``zrp diagnose`` end to end, and the real IRB 120 laser-tracker data when available."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.gap.report import verdict_text
from zrp.kinematics import uniform_joint_values


def _no_nan(name):
    raise AssertionError(f"diagnosis JSON contains {name}; it must be strict JSON")


@pytest.fixture(scope="module")
def csv_file(tmp_path_factory):
    model = zrp.load_model("puma")
    rng = np.random.default_rng(21)
    meas = synthesize(model, uniform_joint_values(model, 150, rng),
                      Injection(joint_offset={3: 1.5e-3}), rng=rng)
    path = tmp_path_factory.mktemp("cli") / "d.csv"
    meas.to_csv(path, deg=True)
    return path


def test_cli_writes_json_report_and_plots(csv_file, tmp_path, capsys):
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["diagnose", "--model", "puma", "--data", str(csv_file), "--deg",
                   "--out", str(out), "--seed", "4"])
    assert rc == 0
    doc = json.loads((out / "diagnosis.json").read_text(), parse_constant=_no_nan)
    for key in ("nominal", "steps", "final", "noise_floor", "unexplained", "split"):
        assert key in doc
    step = doc["steps"][0]
    assert step["effect"] == "joint_offset" and step["joints"] == [3]
    par = step["parameters"][0]
    assert par["name"] == "q3.offset" and par["ci95"][0] < 1.5e-3 < par["ci95"][1]
    for k in ("rms", "p95", "max"):
        assert step[k] > 0
    assert set(doc["split"]["fitting"]).isdisjoint(doc["split"]["withheld"])
    assert doc["unexplained"] is False
    report = (out / "report.md").read_text()
    assert "joint_offset" in report and "shrink.png" in report
    for png in ("shrink.png", "residuals_before_after.png", "residual_vs_joint.png"):
        assert (out / png).stat().st_size > 1000
    assert "wrote" in capsys.readouterr().out
    # never overwrite without --force
    rc = main(["diagnose", "--model", "puma", "--data", str(csv_file), "--deg",
               "--out", str(out)])
    assert rc == 2
    assert "--force" in capsys.readouterr().err


def test_cli_bad_input_is_one_clear_line(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("pose,q1,q2,q3,q4,q5,q6,x,y\n")
    rc = main(["diagnose", "--model", "puma", "--data", str(bad), "--out", str(tmp_path / "o")])
    assert rc == 2
    err = capsys.readouterr().err
    assert "missing column(s) z" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_cli_json_output(csv_file, tmp_path, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["diagnose", "--model", "puma", "--data", str(csv_file), "--deg", "--out",
                   str(tmp_path / "j"), "--json", "--no-plots", "--effects", "joint_offset",
                   "encoder_scale"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out, parse_constant=_no_nan)
    assert doc["effects"] == ["joint_offset"]
    assert not (tmp_path / "j" / "shrink.png").exists()


def test_real_irb120_report_is_believable(irb120_real):
    meas, d = irb120_real.measurements, irb120_real.diagnosis
    assert meas.n_rows == 2946 and len(meas.pose_ids) == 982
    # registration: the tracker is ~3 m away, the reflectors ~150 mm apart on the tool
    assert 0.3 < d.nominal.rms < 3.0  # mm: an uncalibrated industrial arm
    assert d.noise_floor.method == "rigid_links" and d.noise_floor.rms < 0.05
    assert d.steps, "the real robot must show some significant effect"
    assert d.final.rms < 0.7 * d.nominal.rms  # the withheld gap shrinks substantially
    # but far from the instrument's floor: stated plainly, not hidden
    assert d.unexplained is True
    assert "remains that no effect in the library explains" in verdict_text(d)
    # every reported interval is finite and contains its value
    for p in d.final_parameters:
        assert np.isfinite(p.stderr) and p.ci95[0] <= p.value <= p.ci95[1]


def test_cli_residual_model_reports_the_learned_term(csv_file, tmp_path):
    """--residual-model: diagnosis.json carries the learned term's withheld test beside the
    physical model's (here nothing remains to learn: not kept) and the option in settings."""
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["diagnose", "--model", "puma", "--data", str(csv_file), "--deg",
                   "--out", str(out), "--seed", "4", "--residual-model", "--no-plots"])
    assert rc == 0
    doc = json.loads((out / "diagnosis.json").read_text(), parse_constant=_no_nan)
    rm = doc["residual_model"]
    assert doc["settings"]["residual_model"] is True
    assert rm["kept"] is False and rm["withheld_rms_physical"] == doc["final"]["rms"]
    assert doc["remainder"]["structure"]["structured"] is False
