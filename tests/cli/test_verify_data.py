"""``zrp verify --data FRESH.csv``: what a calibration achieved on a fresh measurement
(issue 45), on simulated data (the robot compensated, poses repeated) and on a split of the
real IRB 120 (calibrated on the first 700 poses, verified on the other 282)."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import compensate_program, read_calibration
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
TRUE = Injection(joint_offset={2: 1e-3, 3: -8e-4}, link={3: (0.3, 0.0, -0.2)})
SPAN = np.tile([-1.5, 1.5], (6, 1))


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    rng = np.random.default_rng(8)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 250, rng, SPAN), TRUE, rng=rng)
    root = tmp_path_factory.mktemp("verify")
    meas.to_csv(root / "d.csv")
    with warnings.catch_warnings(record=True):
        assert main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"),
                     "--no-progress", "--out", str(root / "cal")]) == 0
    return root / "cal" / "compensation.json"


def test_a_fresh_measurement_of_the_compensated_robot(calibrated, tmp_path, capsys):
    """A joint program compensated, then the true robot measured at the commands (every
    fifth pose five times more): the achieved RMS within 15 % of the diagnosis's withheld
    prediction, ISO 9283 on the repeated poses, the report page and the plot written."""
    cal = read_calibration(calibrated)
    rng = np.random.default_rng(9)
    program = uniform_joint_values(PUMA, 120, rng, SPAN * 0.9)
    cmd = compensate_program(cal, program, accept_flagged=True).q_command
    q = np.vstack([cmd, np.repeat(cmd[::5], 5, axis=0)])
    fresh = synthesize(PUMA, q, TRUE, rng=rng)  # the tracker has not moved
    fresh.to_csv(tmp_path / "fresh.csv")
    out = tmp_path / "ver"
    assert main(["verify", "--calibration", str(calibrated), "--data",
                 str(tmp_path / "fresh.csv"), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    doc = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    predicted = json.loads(calibrated.read_text(encoding="utf-8"))["withheld_rms"]
    achieved = doc["within_measured_ranges"]["rms"]
    assert doc["predicted_rms"] == predicted
    assert abs(achieved / predicted - 1.0) < 0.15, (achieved, predicted)
    assert doc["all"]["rms"] <= doc["all"]["p95"] * 1.5 and doc["all"]["p95"] <= doc["all"]["max"]
    iso = {a["point"]: a for a in doc["iso9283"]}
    assert set(iso) == {"s1", "s2", "s3"} and iso["s1"]["poses"] == 24
    # repeatability of a perfect robot measured with 0.02 mm noise per coordinate:
    # l = |noise| (mean 0.032 mm) + 3 S_l, about 0.07-0.1 mm
    assert 0.04 < iso["s1"]["rp_mean"] < 0.15
    assert "ISO 9283 on 24 repeated poses of s1" in text and "against the" in text
    page = (out / "verification.md").read_text(encoding="utf-8")
    assert "predicted on its withheld poses" in page and "![errors](verification.png)" in page
    assert (out / "verification.png").stat().st_size > 5000
    rows = list(csv.DictReader(open(out / "errors.csv")))
    assert len(rows) == fresh.n_rows


def test_verify_names_what_it_needs(calibrated, tmp_path, capsys):
    assert main(["verify", "--calibration", str(calibrated)]) == 2
    assert "--data" in capsys.readouterr().err
    bad = synthesize(PUMA, uniform_joint_values(PUMA, 10, np.random.default_rng(1), SPAN),
                     TRUE, rng=np.random.default_rng(2), tool_offsets=[(0.0, 0.0, 50.0)])
    bad.to_csv(tmp_path / "b.csv")  # its only point is s1: known; rename it to an unknown one
    text = (tmp_path / "b.csv").read_text().replace(",s1,", ",probe,")
    (tmp_path / "b.csv").write_text(text)
    assert main(["verify", "--calibration", str(calibrated), "--data",
                 str(tmp_path / "b.csv")]) == 2
    err = capsys.readouterr().err
    assert "probe" in err and "s1, s2, s3" in err


def test_the_real_irb120_verified_on_poses_it_never_saw(shared_dir, tmp_path, capsys):
    src = shared_dir / "data" / "irb120-lasertracker"
    if not (src / "measurements.csv").is_file():
        pytest.skip("the IRB 120 data are not present")
    lines = (src / "measurements.csv").read_text().splitlines()
    head, body = lines[0], lines[1:]
    first = [r for r in body if int(r.split(",")[0]) < 700]
    rest = [r for r in body if int(r.split(",")[0]) >= 700]
    (tmp_path / "cal.csv").write_text("\n".join([head, *first]) + "\n")
    (tmp_path / "fresh.csv").write_text("\n".join([head, *rest]) + "\n")
    with warnings.catch_warnings(record=True):
        assert main(["calibrate", "--model", str(src / "irb120.toml"), "--data",
                     str(tmp_path / "cal.csv"), "--deg", "--no-progress", "--out",
                     str(tmp_path / "cal")]) == 0
    capsys.readouterr()
    assert main(["verify", "--calibration", str(tmp_path / "cal" / "compensation.json"),
                 "--data", str(tmp_path / "fresh.csv"), "--deg", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # measured on this code: 0.4249 mm achieved within the ranges against 0.4236 predicted
    assert doc["rows"] == 846 and doc["poses"] == 282
    assert 0.85 < doc["achieved_to_predicted"] < 1.15
    assert doc["within_measured_ranges"]["rms"] < 0.5 and doc["iso9283"] == []
