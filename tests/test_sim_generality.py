"""The "real" robot and the blind benchmark on arms other than the PUMA (7 joints, an arm
folded upright at q = 0, models in metres)."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

import zrp
from sim.benchmark import BenchmarkConfig
from sim.benchmark.scenarios import DEFAULT_NOISE_MM, draw_scenarios
from sim.effects import HiddenEffects
from sim.measurement import Instrument, measure
from sim.real_robot import RealRobot
from sim.robot_model import _servo_inertias
from zrp.kinematics import forward_kinematics, reachable_poses

EXACT = Instrument(noise_sigma=0.0, rotvec=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0))


def panda_like() -> zrp.Manipulator:
    """A 7R arm with the Franka Panda's published kinematics (mm): at q = 0 it stands upright,
    so joints 1 and 3 see some 20-45x more inertia once it stretches out."""
    axes = [[0, 0, 1], [0, 1, 0], [0, 0, 1], [0, -1, 0], [0, 0, 1], [0, -1, 0], [0, 0, -1]]
    bodies = [[0, 0, 333], [0, 0, 0], [0, 0, 316], [82.5, 0, 0], [-82.5, 0, 384], [0, 0, 0],
              [88, 0, 0], [0, 0, -107]]
    lim = [(-2.8973, 2.8973), (-1.7628, 1.7628), (-2.8973, 2.8973), (-3.0718, -0.0698),
           (-2.8973, 2.8973), (-0.0175, 3.7525), (-2.8973, 2.8973)]
    return zrp.Manipulator.from_arrays(axes, bodies, axial=[0, 0, -1], transverse=[0, 1, 0],
                                       name="panda-like", limits=lim)


def test_servo_gains_are_stable_at_every_pose_of_a_7_axis_arm():
    """Routh for I s^3 + kv s^2 + kp s + kp ki: ki < kv / I at the largest inertia each servo
    sees (before the cap, joints 1 and 3 of this arm diverged: NaN accelerations)."""
    robot = RealRobot(panda_like(), HiddenEffects())
    names = [mujoco.mj_id2name(robot.model, mujoco.mjtObj.mjOBJ_JOINT, j)
             for j in range(robot.model.njnt)]

    class Chain:  # the motor joints, as the builder named them
        motor = [nm for nm in names if nm is not None and "play" not in nm][:7]

    m = robot.nominal
    inertia = _servo_inertias(robot.model, Chain, m.lower, m.upper)
    assert inertia.max(axis=0)[0] > 10 * inertia[0, 0]  # the hostile case is really there
    kv, ki = robot._ids["kv"], robot._ids["ki"]
    assert np.all(ki < kv / inertia.max(axis=0))


def test_a_7_axis_arm_settles_on_its_kinematics_at_stretched_poses():
    model = panda_like()
    q = reachable_poses(model, 4, np.random.default_rng(2))
    robot = RealRobot(model, HiddenEffects())
    run = measure(robot, q, EXACT, np.random.default_rng(0))
    q_link = np.asarray(run.truth["poses"]["q_link"])
    assert np.all(np.isfinite(q_link))
    assert np.max(np.abs(q_link - q)) < 1e-6  # rad
    fk = forward_kinematics(model, q)
    R = np.asarray(fk.rotation)
    tp = np.asarray(robot.tool_points)
    expected = np.asarray(fk.position)[:, None, :] + np.einsum("pij,mj->pmi", R, tp)
    pts = np.asarray(run.truth["poses"]["points_base_noisefree"])
    assert np.max(np.abs(pts - expected)) < 1e-3  # mm, << tracker noise (0.01 mm)


def _in_metres(model: zrp.Manipulator) -> zrp.Manipulator:
    return dataclasses.replace(model.with_arrays(bodies=model.bodies * 1e-3), length_unit="m")


def test_benchmark_noise_default_is_a_tracker_in_any_length_unit():
    """0.01-0.03 mm, not 0.01-0.03 of whatever the model's unit is (10-30 mm on a model in
    metres hid every effect: 0 of 17 visible)."""
    puma = zrp.load_model("puma")
    cfg = BenchmarkConfig(scenarios=6)
    assert cfg.noise_range(puma) == DEFAULT_NOISE_MM == (0.01, 0.03)
    lo, hi = cfg.noise_range(_in_metres(puma))
    assert lo == pytest.approx(1e-5, rel=1e-12) and hi == pytest.approx(3e-5, rel=1e-12)
    sig_mm = [s.noise_sigma for s in draw_scenarios(puma, cfg)]
    sig_m = [s.noise_sigma for s in draw_scenarios(_in_metres(puma), cfg)]
    np.testing.assert_allclose(np.array(sig_m) * 1e3, sig_mm, rtol=1e-12)
    # an explicit range stays in the model's unit
    assert BenchmarkConfig(noise=(0.5, 1.0)).noise_range(_in_metres(puma)) == (0.5, 1.0)
