"""MuJoCo playback: consistency with ZRP direct kinematics, and dynamic playback."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mjcf
import sim
import zrp
import zrp.rotations
from tests.arms import perturbed_puma, random_arm
from zrp.errors import InputError

POS_TOL_MM = 1e-9
ROT_TOL_RAD = 1e-12


@pytest.fixture(scope="module")
def puma_circle():
    from zrp.paper.scenario import puma_circle_ik

    ik = puma_circle_ik(steps=180)
    return ik.t, ik.q


def test_consistency_puma_circle_nominal(puma_circle):
    _, q = puma_circle
    model = zrp.load_model("puma")
    report = sim.consistency_check(model, q)
    assert len(report.position_error) == len(q)
    assert report.max_position_error_mm <= POS_TOL_MM, report.summary()
    assert report.max_orientation_error <= ROT_TOL_RAD, report.summary()
    assert report.passed()


def test_consistency_puma_circle_perturbed(puma_circle):
    _, q = puma_circle
    model = perturbed_puma()
    report = sim.consistency_check(model, q)
    assert report.passed(POS_TOL_MM, ROT_TOL_RAD), report.summary()
    # the perturbed arm really is elsewhere: MuJoCo sees the perturbation ZRP predicts
    nominal = sim.kinematic_playback(zrp.load_model("puma"), q)
    actual = sim.kinematic_playback(model, q)
    assert np.max(np.linalg.norm(actual.position - nominal.position, axis=1)) > 0.1  # mm


@pytest.mark.parametrize("seed,n,unit,prismatic", [
    (11, 6, "mm", False), (12, 7, "mm", True), (13, 3, "m", False), (14, 6, "m", True),
    (15, 1, "mm", False),
])
def test_consistency_random_arms(seed, n, unit, prismatic):
    model = random_arm(seed, n=n, unit=unit, prismatic=prismatic)
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, size=(200, n))
    q[:, model.prismatic] = rng.uniform(-300, 300, size=(200, int(model.prismatic.sum()))) * (
        1.0 if unit == "mm" else 1e-3)
    report = sim.consistency_check(model, q)
    assert report.passed(POS_TOL_MM, ROT_TOL_RAD), report.summary()


def test_playback_shapes_and_single_pose():
    model = zrp.load_model("stanford")
    q = np.zeros(model.n)
    poses = sim.kinematic_playback(model, q)
    assert poses.position.shape == (1, 3) and poses.frame.shape == (1, 3, 3)
    fk = zrp.forward_kinematics(model, q)
    np.testing.assert_allclose(poses.position[0], fk.position, atol=1e-9)
    np.testing.assert_allclose(poses.axial[0], model.end_effector.axial, atol=1e-15)


def test_playback_bad_inputs():
    model = zrp.load_model("puma")
    with pytest.raises(InputError, match=r"q: expected shape \(\.\.\., 6\)"):
        sim.kinematic_playback(model, np.zeros((4, 5)))
    q = np.zeros((3, 6))
    q[1, 2] = np.nan
    with pytest.raises(InputError, match="joint 3"):
        sim.kinematic_playback(model, q)
    arm = mjcf.build(model)
    with pytest.raises(InputError, match="different model"):
        sim.consistency_check(perturbed_puma(), q[:1], arm=arm)


def test_rotation_angle_small_angles():
    from zrp.rotations.rodrigues import er_from_axis_angle, matrix_from_er

    for angle in (1e-14, 1e-9, 1e-3, 1.0, 3.0):
        r = matrix_from_er(er_from_axis_angle([0.0, 0.6, 0.8], angle))
        assert zrp.rotations.rotation_angle(np.eye(3), r) == pytest.approx(angle, rel=1e-9,
                                                                            abs=1e-16)


def test_dynamic_playback_gravity_and_compensation(puma_circle):
    t, q = puma_circle
    model = zrp.load_model("puma")
    comp_opts = sim.default_dynamic_options(model, gravity_compensation=True)
    plain = sim.dynamic_playback(model, t, q, settle_s=0.5)
    comp = sim.dynamic_playback(model, t, q, settle_s=0.5, options=comp_opts)
    no_ff = sim.dynamic_playback(model, t, q, settle_s=0.5, options=comp_opts,
                                 velocity_feedforward=False)
    assert plain.tracking_error.shape == (len(t),)
    assert np.all(np.isfinite(plain.tracking_error))
    # At rest under gravity with finite gains the arm sags (static error tau_g / kp) ...
    assert 0.5 < plain.tracking_error[0] < 50.0  # mm
    # ... and with gravity compensated it does not sag at all.
    assert comp.tracking_error[0] < 1e-6  # mm
    # While moving: compensation and rate feedforward each reduce the added error.
    assert comp.max_tracking_error < plain.max_tracking_error
    assert comp.max_tracking_error < no_ff.max_tracking_error
    # The servos track: joint errors stay small.
    assert np.max(np.abs(plain.q_actual - plain.q_command)) < 0.05
    # The kinematic reference is ZRP direct kinematics of the commanded joints.
    np.testing.assert_allclose(plain.position_kinematic,
                               zrp.forward_kinematics(model, q).position, atol=1e-9)
    assert "tracking error" in plain.summary()


def test_dynamic_playback_bad_inputs(puma_circle):
    t, q = puma_circle
    model = zrp.load_model("puma")
    with pytest.raises(InputError, match="strictly increasing"):
        sim.dynamic_playback(model, t[::-1], q)
    with pytest.raises(InputError, match="actuators"):
        sim.dynamic_playback(model, t, q, options=mjcf.MJCFOptions())
    with pytest.raises(InputError, match="settle_s"):
        sim.dynamic_playback(model, t, q, settle_s=-1)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 8), p_prismatic=st.sampled_from([0, 0.3]))
def test_consistency_property_random_arms(seed, n, p_prismatic):
    """Any arm the toolkit can represent: MuJoCo and ZRP agree to the stated bounds."""
    from zrp.testing import random_arm as zrp_random_arm

    rng = np.random.default_rng(seed)
    model = zrp_random_arm(rng, n, p_prismatic=p_prismatic)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(20, n))
    q[:, model.prismatic] *= 100.0  # mm
    report = sim.consistency_check(model, q)
    assert report.passed(POS_TOL_MM, ROT_TOL_RAD), report.summary()


def test_dynamic_playback_prismatic_arm_with_rod_inertias():
    model = zrp.load_model("stanford")
    t = np.linspace(0.0, 1.0, 51)
    q = np.outer(np.sin(np.pi * t), np.where(model.prismatic, 50.0, 0.4))  # rad / mm
    res = sim.dynamic_playback(model, t, q, settle_s=0.3)
    assert res.options.inertia == "rods"
    assert np.all(np.isfinite(res.tracking_error)) and res.max_tracking_error > 0
    comp = sim.dynamic_playback(
        model, t, q, settle_s=0.3,
        options=sim.default_dynamic_options(model, gravity_compensation=True))
    assert comp.tracking_error[0] < 1e-6 < res.tracking_error[0]
