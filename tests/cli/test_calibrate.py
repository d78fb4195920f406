"""``zrp calibrate``, ``zrp compensate`` and ``zrp plan`` end to end."""

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


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    rng = np.random.default_rng(21)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 150, rng),
                      Injection(joint_offset={3: 1.5e-3}, link={3: (0.3, 0.0, -0.2)}), rng=rng)
    root = tmp_path_factory.mktemp("cal")
    meas.to_csv(root / "d.csv", deg=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"), "--deg",
                     "--out", str(root / "out")]) == 0
    return root


def test_calibrate_writes_model_and_compensation(calibrated, capsys):
    out = calibrated / "out"
    assert {"calibrated.toml", "compensation.json", "diagnosis.json"} <= {
        p.name for p in out.iterdir()}
    doc = json.loads((out / "compensation.json").read_text())
    assert doc["model_file"] == "calibrated.toml" and set(doc["tool_points"]) == {
        "s1", "s2", "s3"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", "puma", "--data", str(calibrated / "d.csv"),
                   "--deg", "--out", str(out)])
    assert rc == 2 and "--force" in capsys.readouterr().err


def test_compensate_program_and_limits(calibrated, tmp_path, capsys):
    q = uniform_joint_values(PUMA, 12, np.random.default_rng(3), np.tile([-2, 2], (6, 1)))
    tfile = tmp_path / "prog.csv"
    with open(tfile, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["target", *[f"q{k}" for k in range(1, 7)]])
        for i, row in enumerate(np.degrees(q)):
            w.writerow([f"T{i}", *row])
    comp_json = calibrated / "out" / "compensation.json"
    out = tmp_path / "cmd.csv"
    rc = main(["compensate", "--calibration", str(comp_json), "--targets", str(tfile),
               "--deg", "--out", str(out), "--accept-flagged"])  # random rows: some flagged
    assert rc == 0
    rows = list(csv.DictReader(open(out)))
    ref = compensate_program(read_calibration(comp_json), q, accept_flagged=True)
    got = np.radians([[float(r[f"q{k}[deg]"]) for k in range(1, 7)] for r in rows])
    assert np.allclose(got, ref.q_command, atol=1e-12)
    assert all(r["converged"] == "1" for r in rows)
    i = int(np.argmin(q[:, 0]))
    lo1 = np.degrees(q[i, 0]) + 1e-3   # the lowest joint-1 program row is below this limit
    lim = ",".join([f"{lo1}:180"] + ["-180:180"] * 5)
    rc = main(["compensate", "--calibration", str(comp_json), "--targets", str(tfile),
               "--deg", "--out", str(tmp_path / "c2.csv"), f"--limits={lim}"])
    err = capsys.readouterr().err
    assert rc == 2 and f"target T{i}: " in err and "joint 1 " in err
    assert "outside its limit" in err


def test_plan_cli(tmp_path, capsys):
    out = tmp_path / "plan.csv"
    rc = main(["plan", "--model", "puma", "--poses", "20", "--effects", "joint_offset",
               "--out", str(out), "--floor", "-400", "--candidates", "200", "--json"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    assert "q1.offset" in doc["unidentifiable"]
    assert len(list(csv.DictReader(open(out)))) == 20
