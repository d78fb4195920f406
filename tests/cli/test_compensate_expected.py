"""``zrp compensate`` says what the user will get (issue 45): the accuracy the diagnosis
measured on withheld poses, each target outside the measured joint ranges flagged, never the
calibrated model's agreement with itself; tracker-frame targets need ``--point``."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    rng = np.random.default_rng(21)
    q = uniform_joint_values(PUMA, 120, rng, np.tile([-1.5, 1.5], (6, 1)))
    meas = synthesize(PUMA, q, Injection(joint_offset={3: 1.5e-3}, link={3: (0.3, 0.0, -0.2)}),
                      rng=rng)
    root = tmp_path_factory.mktemp("cal")
    meas.to_csv(root / "d.csv")
    with warnings.catch_warnings(record=True):
        assert main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"),
                     "--no-progress", "--out", str(root / "out")]) == 0
    return root, meas


def _program(path, q, ids, xyz=None):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["target", *[f"q{k}" for k in range(1, 7)], *(["x", "y", "z"] if xyz
                                                                  is not None else [])])
        for i, row in enumerate(q):
            w.writerow([ids[i], *row, *([] if xyz is None else xyz[i])])


def test_the_expected_error_is_the_withheld_one_and_far_targets_are_flagged(
        calibrated, tmp_path, capsys):
    root, meas = calibrated
    comp = root / "out" / "compensation.json"
    withheld = json.loads(comp.read_text(encoding="utf-8"))["withheld_rms"]
    q = np.vstack([meas.q_pose[:6], [[2.8, 0.0, 0.0, 0.0, 0.0, 0.0]]])  # the last: far out
    _program(tmp_path / "p.csv", q, [f"T{i}" for i in range(6)] + ["FAR"])
    argv = ["compensate", "--calibration", str(comp), "--targets", str(tmp_path / "p.csv"),
            "--out", str(tmp_path / "c.csv"), "--accept-flagged"]
    assert main([*argv, "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["expected_rms"] == withheld and 0.0 < withheld < 0.2
    assert s["outside_measured_targets"] == ["FAR"] and s["inside"] == 6
    assert s["solve_rms"] < 1e-6 < s["correction_rms"]  # the solve is convergence only
    assert main([*argv, "--force"]) == 0
    text = capsys.readouterr().out
    assert f"expected error {withheld:.4g} mm RMS, what the diagnosis measured on withheld" in text
    assert "1 target(s) outside those ranges (FAR" in text
    assert "predicted RMS error" not in text
    rows = list(csv.DictReader(open(tmp_path / "c.csv")))
    assert [r["outside_measured"] for r in rows] == ["0"] * 6 + ["1"]


def test_tracker_frame_targets_without_a_point_are_refused(calibrated, tmp_path, capsys):
    root, meas = calibrated
    comp = root / "out" / "compensation.json"
    rows = np.flatnonzero(meas.point == "s2")[:4]
    _program(tmp_path / "t.csv", meas.q[rows], [f"T{i}" for i in range(4)], meas.xyz[rows])
    argv = ["compensate", "--calibration", str(comp), "--targets", str(tmp_path / "t.csv"),
            "--out", str(tmp_path / "c.csv"), "--frame", "instrument"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--point" in err and "s1, s2, s3" in err
    assert main([*argv, "--point", "s2"]) == 0
    assert "expected error" in capsys.readouterr().out
