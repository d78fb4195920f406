"""Full-pose identification (zrp.gap.fit.fullpose, issue 11): measured orientations beside the
positions, each weighted by its own noise.

References: the synthetic robot is the nominal model with its axis tilted exactly
(u' = (u + a t1) / |.|), measured through zrp.forward_kinematics (not the Problem code); the
orientation Jacobian is checked against central finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import zrp
from tests.measured import BASE_ROTATION, full_pose_measurements
from zrp.errors import InputError
from zrp.gap import Measurements
from zrp.gap.fit.fullpose import fit_full_pose, orientation_residual, pose_rotations
from zrp.gap.model.context import Context
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.model.problem import Problem
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
TILT = 1.0e-3          # rad, axis 6 towards its first tangent
SIGMA_P, SIGMA_O = 0.02, 5e-5   # mm, rad
RT = Rotation.from_rotvec([0.3, -0.2, 0.1]).as_matrix()
# one reflector 3 mm off the wrist centre: positions see the axis-6 tilt only through 3 mm
TOOL = np.array([[3.0, 0.0, 127.0]])


def _measure(n_poses: int, seed: int) -> Measurements:
    return full_pose_measurements(PUMA, n_poses, seed, tilt=(6, 0, TILT), tools=TOOL,
                                  probe_rotation=RT, sigma_position=SIGMA_P,
                                  sigma_orientation=SIGMA_O)


def _specs(ctx):
    return registration_parameters(ctx) + effect_parameters(ctx, "axis_misalignment")[0]


def test_orientation_jacobian_matches_finite_differences():
    ctx = Context(PUMA, _measure(12, 0))
    specs = _specs(ctx)
    prob = Problem(ctx, specs, np.arange(12), BASE_ROTATION)
    rng = np.random.default_rng(1)
    theta = rng.normal(scale=1e-3, size=len(specs))
    psi = np.array([0.01, -0.02, 0.005])
    meas = pose_rotations(ctx)
    _, J = orientation_residual(prob, theta, psi, RT, meas)
    h = 1e-6
    for j in range(len(specs) + 3):
        dp = np.zeros(len(specs) + 3)
        dp[j] = h
        ep, _ = orientation_residual(prob, theta + dp[:-3], psi + dp[-3:], RT, meas)
        em, _ = orientation_residual(prob, theta - dp[:-3], psi - dp[-3:], RT, meas)
        np.testing.assert_allclose(J[:, :, j], (ep - em) / (2 * h), atol=1e-7)


def test_orientations_recover_an_axis_tilt_positions_see_weakly():
    ctx = Context(PUMA, _measure(80, 2))
    specs = _specs(ctx)
    pos = fit_full_pose(ctx, specs, np.arange(80), orientation=False)
    full = fit_full_pose(ctx, specs, np.arange(80))
    name = "u6.t1"
    # positions alone: the tilt is hardly determined; with orientations, to a few percent
    assert pos.std(name) > 10 * full.std(name)
    assert abs(full.value(name) - TILT) < 4 * full.std(name)
    assert full.std(name) < 0.05 * TILT
    # the noise of each block is found: sigma_o estimated from the residuals
    assert full.sigma_orientation == pytest.approx(SIGMA_O, rel=0.25)
    np.testing.assert_allclose(full.probe_rotation, RT, atol=1e-3)


def test_full_pose_needs_orientations():
    rng = np.random.default_rng(0)
    q = uniform_joint_values(PUMA, 10, rng, np.tile([-2, 2], (6, 1)))
    ctx = Context(PUMA, Measurements.from_arrays(np.arange(10), q, rng.normal(size=(10, 3))))
    with pytest.raises(InputError, match="qw, qx, qy, qz"):
        fit_full_pose(ctx, registration_parameters(ctx), np.arange(10))
