"""Guarded commands (issue 33): ``zrp compensate`` refuses, by default, targets whose commands
lie outside the joint ranges the calibration measured, and near-singular ones (relative to the
arm's own conditioning, not an absolute 1e-3); with --accept-flagged it compensates them and
flags them per row."""

from __future__ import annotations

import csv
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import compensate_program, read_calibration
from zrp.calibration.guards import NearSingularTargetError, UnmeasuredTargetError
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
SPAN = 1.0  # rad: the data measure every joint within +-SPAN


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    rng = np.random.default_rng(11)
    q = uniform_joint_values(PUMA, 100, rng, np.tile([-SPAN, SPAN], (6, 1)))
    meas = synthesize(PUMA, q, Injection(joint_offset={2: 1e-3}), rng=rng)
    root = tmp_path_factory.mktemp("guard")
    meas.to_csv(root / "d.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"),
                     "--effects", "joint_offset", "--no-progress",
                     "--out", str(root / "out")]) == 0
    return root / "out" / "compensation.json"


def _program(path, rows: dict[str, list[float]]):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["target", *[f"q{k}" for k in range(1, 7)]])
        for name, q in rows.items():
            w.writerow([name, *q])
    return path


OK = [0.3, -0.4, 0.5, 0.2, 0.6, -0.3]
BEYOND = [0.3, -0.4, 0.5, 0.2, 0.6, -0.3]
BEYOND[0] = SPAN + 0.6          # joint 1 0.6 rad beyond the measured range
WRIST = [0.3, -0.4, 0.5, 0.2, 0.01, -0.3]   # q5 = 0.01 rad: the PUMA's wrist singularity


def test_ranges_are_recorded(calibrated):
    r = read_calibration(calibrated).conditions.joint_ranges
    assert r is not None and len(r) == 6
    assert all(-SPAN <= lo < -0.8 and 0.8 < hi <= SPAN for lo, hi in r)


def test_outside_the_measured_range_is_refused_then_flagged(calibrated, tmp_path, capsys):
    prog = _program(tmp_path / "p.csv", {"ok": OK, "far": BEYOND})
    args = ["compensate", "--calibration", str(calibrated), "--targets", str(prog),
            "--out", str(tmp_path / "c.csv")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "target far: the command of joint 1 is 1.6" in err
    assert "outside the range the calibration measured" in err and "--accept-flagged" in err
    assert not (tmp_path / "c.csv").exists()
    assert main([*args, "--accept-flagged"]) == 0
    rows = {r["target"]: r for r in csv.DictReader(open(tmp_path / "c.csv"))}
    assert rows["far"]["outside_measured"] == "1" and rows["ok"]["outside_measured"] == "0"


def test_near_singular_is_relative_to_the_arm(calibrated, tmp_path, capsys):
    cal = read_calibration(calibrated)
    q = np.array([OK, WRIST])
    with pytest.raises(NearSingularTargetError, match="target 2: the command is near a "
                       "singularity"):
        compensate_program(cal, q)
    comp = compensate_program(cal, q, accept_flagged=True)
    assert comp.near_singular.tolist() == [False, True]
    # the absolute threshold of 0.4.0 (1e-3) would not have flagged it
    assert comp.sigma_min[1] > 1e-3
    # the command line: refused, then flagged per row
    prog = _program(tmp_path / "p.csv", {"ok": OK, "wrist": WRIST})
    args = ["compensate", "--calibration", str(calibrated), "--targets", str(prog),
            "--out", str(tmp_path / "c.csv")]
    assert main(args) == 2 and "target wrist: the command is near a singularity" in (
        capsys.readouterr().err)
    assert main([*args, "--accept-flagged"]) == 0
    rows = {r["target"]: r for r in csv.DictReader(open(tmp_path / "c.csv"))}
    assert rows["wrist"]["near_singular"] == "1" and rows["ok"]["near_singular"] == "0"


def test_the_api_refuses_outside_the_range(calibrated):
    cal = read_calibration(calibrated)
    with pytest.raises(UnmeasuredTargetError, match="joint 1"):
        compensate_program(cal, np.array([BEYOND]))
