"""Full-pose data in the calibration (zrp.calibration.fullpose, ``zrp calibrate``): the
diagnosis's final model refitted with the measured orientations is more precise and predicts
the withheld positions as well. The synthetic robot (nominal PUMA, joint-2 offset, axis-5
tilt) is measured through zrp.forward_kinematics, not the calibration code."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import zrp
from zrp.calibration.fullpose import full_pose_calibration
from zrp.cli.app import main
from zrp.errors import InputError
from zrp.gap import Measurements, diagnose, load_measurements
from zrp.kinematics import uniform_joint_values
from zrp.kinematics.identification import axis_tangents

PUMA = zrp.load_model("puma")
TOOLS = np.array([(50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -70.0, 40.0)])
RB = Rotation.from_rotvec([0.02, -0.01, 0.8]).as_matrix()
TB = np.array([1500.0, -300.0, 200.0])
RT = Rotation.from_rotvec([0.2, 0.1, -0.3]).as_matrix()


def _measure(quat: bool = True) -> Measurements:
    rng = np.random.default_rng(7)
    P = 150
    q = uniform_joint_values(PUMA, P, rng, np.tile([-2.5, 2.5], (6, 1)))
    axes = np.array(PUMA.axes, dtype=float)
    v = axes[4] + 1.5e-3 * axis_tangents(axes[4])[0]
    axes[4] = v / np.linalg.norm(v)
    fk = zrp.forward_kinematics(PUMA.with_arrays(axes=axes), q + np.array([0, 1e-3, 0, 0, 0, 0]))
    y = fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, TOOLS)
    xyz = y @ RB.T + TB + rng.normal(scale=0.02, size=y.shape)
    noise = Rotation.from_rotvec(rng.normal(scale=1e-4, size=(P, 3))).as_matrix()
    qt = Rotation.from_matrix(noise @ RB @ fk.rotation @ RT).as_quat()[:, [3, 0, 1, 2]]
    return Measurements.from_arrays(np.repeat(np.arange(P), 3), np.repeat(q, 3, axis=0),
                                    xyz.reshape(-1, 3), point=np.tile(["s1", "s2", "s3"], P),
                                    quat=np.repeat(qt, 3, axis=0) if quat else None)


def test_orientations_sharpen_the_calibration():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        diag = diagnose(PUMA, _measure(), seed=0)
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
        no_quat = diagnose(PUMA, _measure(quat=False), seed=0)
    with pytest.raises(InputError, match="qw, qx, qy, qz"):
        full_pose_calibration(no_quat)


def test_calibrate_uses_measured_orientations(tmp_path, capsys):
    _measure().to_csv(tmp_path / "d.csv")
    assert load_measurements(tmp_path / "d.csv", PUMA).quat is not None   # round trip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", "puma", "--data", str(tmp_path / "d.csv"),
                   "--out", str(tmp_path / "out")])
    assert rc == 0
    assert "full pose (measured orientations" in capsys.readouterr().out
