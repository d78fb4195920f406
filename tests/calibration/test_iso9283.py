"""ISO 9283 AP / RP on repeated poses against closed forms: pure isotropic noise gives
RP = E|l| + 3 sd|l| with |l| Maxwell-distributed (2 sqrt(2/pi) sigma, sqrt(3 - 8/pi) sigma),
and AP equals the distance between the injected robot's and the model's tool point."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.calibration import CalibratedRobot
from zrp.calibration.iso9283 import pose_accuracy
from zrp.errors import InputError
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.rotations import matrix_from_rotvec

PUMA = zrp.load_model("puma")
TOOLS = np.array([(50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -70.0, 40.0)])
SIGMA = 0.02
INJ = Injection(joint_offset={2: 1e-3})


def _model_robot():
    """The nominal model with the true registration of zrp.gap.synthesize's defaults."""
    return CalibratedRobot(PUMA, PUMA, matrix_from_rotvec([0.02, -0.01, 0.8]),
                           np.array([1500.0, -300.0, 200.0]), ("s1", "s2", "s3"), TOOLS,
                           np.zeros(6))


def test_ap_rp_closed_forms():
    rng = np.random.default_rng(3)
    q0 = uniform_joint_values(PUMA, 10, rng)
    q = np.tile(q0, (30, 1))                      # 10 poses, 30 cycles, interleaved
    meas = synthesize(PUMA, q, INJ, rng=rng, noise_sigma=SIGMA)
    acc = pose_accuracy(meas, _model_robot(), "s1")
    assert acc.repeats.tolist() == [30] * 10
    true = synthesize(PUMA, q0, INJ, rng=rng, noise_sigma=0.0)
    true_s1 = true.xyz[np.asarray(true.point) == "s1"]
    want_ap = np.linalg.norm(true_s1 - _model_robot().predict(q0, "s1"), axis=1)
    order = [int(np.flatnonzero(np.all(np.isclose(q0, a), axis=1))[0]) for a in acc.q]
    assert np.abs(acc.ap - want_ap[order]).max() < 4 * SIGMA / np.sqrt(30)
    rp_pure = SIGMA * (2 * np.sqrt(2 / np.pi) + 3 * np.sqrt(3 - 8 / np.pi)) * np.sqrt(29 / 30)
    assert acc.rp.mean() == pytest.approx(rp_pure, rel=0.1)


def test_needs_repeats():
    rng = np.random.default_rng(0)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 20, rng), INJ, rng=rng)
    with pytest.raises(InputError, match="min_repeats"):
        pose_accuracy(meas, _model_robot(), "s1")


def test_orientation_ap_rp():
    """AP_abc: the rotation between the model's and the injected robot's hand frames (here
    a joint-2 offset), from zrp.forward_kinematics; RP_abc: 3 sigma for Gaussian noise."""
    from scipy.spatial.transform import Rotation

    from zrp.gap import Measurements

    rng = np.random.default_rng(4)
    q0 = uniform_joint_values(PUMA, 8, rng)
    q = np.tile(q0, (30, 1))
    rb = matrix_from_rotvec([0.02, -0.01, 0.8])
    rt = Rotation.from_rotvec([0.1, 0.2, -0.3]).as_matrix()
    true = zrp.forward_kinematics(PUMA, q + np.array([0, 1e-3, 0, 0, 0, 0]))
    sig_o = 1e-4
    noise = Rotation.from_rotvec(rng.normal(scale=sig_o, size=(len(q), 3))).as_matrix()
    quat = Rotation.from_matrix(noise @ rb @ true.rotation @ rt).as_quat()[:, [3, 0, 1, 2]]
    xyz = (true.position + true.rotation @ TOOLS[0]) @ rb.T + np.array([1500.0, -300.0, 200.0])
    meas = Measurements.from_arrays(np.arange(len(q)), q, xyz, point=["s1"] * len(q),
                                    quat=quat)
    acc = pose_accuracy(meas, _model_robot(), "s1", probe_rotation=rt)
    nom = zrp.forward_kinematics(PUMA, acc.q)        # acc.q: the repeated poses, its order
    t8 = zrp.forward_kinematics(PUMA, acc.q + np.array([0, 1e-3, 0, 0, 0, 0]))
    want = Rotation.from_matrix(np.swapaxes(nom.rotation @ rt, 1, 2)
                                @ t8.rotation @ rt).as_rotvec()
    np.testing.assert_allclose(acc.ap_abc, want, atol=4 * sig_o / np.sqrt(30))
    assert np.abs(want).max() > 5e-4                  # the offset shows in the angles
    np.testing.assert_allclose(np.median(acc.rp_abc), 3 * sig_o, rtol=0.2)
    assert "ap_abc_rad" in acc.to_dict()
    no_quat = pose_accuracy(Measurements.from_arrays(np.arange(len(q)), q, xyz,
                                                     point=["s1"] * len(q)),
                            _model_robot(), "s1")
    assert no_quat.ap_abc is None and "ap_abc_rad" not in no_quat.to_dict()
