"""Full-pose data in the calibration (zrp.calibration.fullpose, ``zrp calibrate``): the
diagnosis's final model refitted with the measured orientations is more precise and predicts
the withheld positions as well. The synthetic robot (nominal PUMA, joint-2 offset, axis-5
tilt; tests/measured.py) is measured through zrp.forward_kinematics, not the calibration
code."""

from __future__ import annotations

import warnings

import pytest

import zrp
from tests.measured import puma_full_pose
from zrp.calibration.fullpose import full_pose_calibration
from zrp.cli.app import main
from zrp.errors import InputError
from zrp.gap import diagnose, load_measurements

PUMA = zrp.load_model("puma")


def test_orientations_sharpen_the_calibration(full_pose_diagnosis):
    diag = full_pose_diagnosis
    assert diag.effects[0] == "joint_offset"
    full = full_pose_calibration(diag)
    s = full.summary()
    assert s["std_ratio_median"] < 0.9 and s["std_ratio_min"] < 0.7   # q2: 0.98, q4: 0.62
    assert full.withheld_rms <= 1.05 * full.withheld_rms_position_only
    assert full.fit.sigma_orientation == pytest.approx(1e-4, rel=0.25)
    assert full.withheld_orientation_rms < 3e-4
    assert full.robot.withheld_rms == diag.final.rms      # for the record: the diagnosis's
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        no_quat = diagnose(PUMA, puma_full_pose(quat=False), seed=0)
    with pytest.raises(InputError, match="qw, qx, qy, qz"):
        full_pose_calibration(no_quat)


def test_calibrate_uses_measured_orientations(tmp_path, capsys):
    puma_full_pose().to_csv(tmp_path / "d.csv")
    assert load_measurements(tmp_path / "d.csv", PUMA).quat is not None   # round trip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", "puma", "--data", str(tmp_path / "d.csv"),
                   "--out", str(tmp_path / "out")])
    assert rc == 0
    assert "full pose (measured orientations" in capsys.readouterr().out
