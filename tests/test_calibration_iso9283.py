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
