"""The "real" robot and the blind benchmark on arms other than the PUMA (7 joints, an arm
folded upright at q = 0, models in metres)."""

from __future__ import annotations

import dataclasses
import json

import mujoco
import numpy as np
import pytest

import zrp
from sim.robot.effects import HiddenEffects
from sim.robot.instrument import Instrument
from sim.robot.measurement import measure
from sim.robot.real import RealRobot
from sim.robot.servo import servo_inertias
from sim.studies.benchmark import BenchmarkConfig
from sim.studies.benchmark.scenarios import DEFAULT_NOISE_MM, draw_scenarios, pose_limits
from zrp.cli import main
from zrp.kinematics import forward_kinematics, reachable_poses
from zrp.testing import PANDA_LIMITS

EXACT = Instrument(noise_sigma=0.0, rotvec=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0))


def panda_like() -> zrp.Manipulator:
    """A 7R arm with the Franka Panda's published kinematics (mm): at q = 0 it stands upright,
    so joints 1 and 3 see some 20-45x more inertia once it stretches out."""
    axes = [[0, 0, 1], [0, 1, 0], [0, 0, 1], [0, -1, 0], [0, 0, 1], [0, -1, 0], [0, 0, -1]]
    bodies = [[0, 0, 333], [0, 0, 0], [0, 0, 316], [82.5, 0, 0], [-82.5, 0, 384], [0, 0, 0],
              [88, 0, 0], [0, 0, -107]]
    return zrp.Manipulator.from_arrays(axes, bodies, axial=[0, 0, -1], transverse=[0, 1, 0],
                                       name="panda-like", limits=PANDA_LIMITS)


def test_servo_gains_are_stable_at_every_pose_of_a_7_axis_arm():
    """Routh for I s^3 + kv s^2 + kp s + kp ki: ki < kv / I at the largest inertia each servo
    sees (before the cap, joints 1 and 3 of this arm diverged: NaN accelerations)."""
    robot = RealRobot(panda_like(), HiddenEffects())
    names = [mujoco.mj_id2name(robot.model, mujoco.mjtObj.mjOBJ_JOINT, j)
             for j in range(robot.model.njnt)]

    motor = [nm for nm in names if nm is not None and "play" not in nm][:7]
    m = robot.nominal
    inertia = servo_inertias(robot.model, motor, m.lower, m.upper)
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


def test_benchmark_poses_move_a_slide_and_keep_within_the_limits():
    """A prismatic joint travels +-10 % of the reach (it moved +-2.5 length units: 5 mm of the
    Stanford arm's 1079 mm, too little for the diagnosis to place a slide's play on it), and
    a joint's own limits bound its poses (the Panda's joint 4 is never positive)."""
    stanford = zrp.load_model("stanford")
    lim = pose_limits(stanford)
    np.testing.assert_allclose(lim[2], [-0.1 * stanford.reach, 0.1 * stanford.reach])
    np.testing.assert_array_equal(lim[[0, 1, 3, 4, 5]], np.tile([-2.5, 2.5], (5, 1)))
    panda = panda_like()
    lim = pose_limits(panda)
    assert np.all(lim[:, 0] >= panda.lower) and np.all(lim[:, 1] <= panda.upper)
    assert lim[3, 1] == pytest.approx(-0.0698)
    puma = zrp.load_model("puma")
    np.testing.assert_array_equal(pose_limits(puma), np.tile([-2.5, 2.5], (6, 1)))
    # the core samplers use the same default: random poses within the model's own limits
    q = reachable_poses(panda, 300, np.random.default_rng(2))
    assert np.all(q >= panda.lower) and np.all(q <= panda.upper) and np.all(q[:, 3] < 0)
    qs = zrp.uniform_joint_values(stanford, 300, np.random.default_rng(2))
    assert np.abs(qs[:, 2]).max() > 0.05 * stanford.reach  # the slide moves (was +-2.5 mm)


def test_benchmark_draws_lengths_for_a_slide_and_no_cyclic_error_on_it():
    stanford = zrp.load_model("stanford")
    cfg = BenchmarkConfig(scenarios=60, pair_fraction=0.0, none_fraction=0.0,
                          effects=("joint_offset", "backlash", "cyclic_error"))
    slide = {"joint_offset": [], "backlash": []}
    for s in draw_scenarios(stanford, cfg):
        assert 3 not in s.effects.cyclic_error  # the diagnosis has no cyclic error on slides
        for name, got in slide.items():
            got += [abs(v) for k, v in getattr(s.effects, name).items() if k == 3]
    for name, got in slide.items():
        assert got, name  # the slide was drawn at least once in 60 scenarios
        # 0.2-1.6 mrad-equivalent of the reach: 0.017-0.14 mm, not 0.2-1.6 um
        assert all(0.015 < v < 0.15 for v in got), (name, got)


def test_benchmark_one_reflector():
    cfg = BenchmarkConfig(reflectors=1)
    puma = zrp.load_model("puma")
    tp = np.asarray(cfg.robot_options(puma).tool_points)
    assert tp.shape == (1, 3)
    with pytest.raises(zrp.InputError, match="reflectors"):
        BenchmarkConfig(reflectors=4)


def test_cli_measure_default_noise_is_20_um_in_any_length_unit(tmp_path, capsys):
    path = tmp_path / "puma_m.toml"
    zrp.save_model(_in_metres(zrp.load_model("puma")), path)
    assert main(["measure", "--model", str(path), "--poses", "8",
                 "--out", str(tmp_path / "m.csv"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["noise_sigma"] == pytest.approx(2e-5, rel=1e-12)  # not 0.02 m


def test_cli_plan_default_noise_is_20_um_in_any_length_unit(tmp_path, capsys):
    """The predicted standard deviations of a plan for the PUMA in m match those in mm (the
    default noise was 0.02 model units: 20 mm in metres, 1000x too pessimistic)."""
    path = tmp_path / "puma_m.toml"
    zrp.save_model(_in_metres(zrp.load_model("puma")), path)
    std = {}
    for model, floor in (("puma", "-400"), (str(path), "-0.4")):
        assert main(["plan", "--model", model, "--poses", "20", "--effects", "joint_offset",
                     "--out", str(tmp_path / "p.csv"), "--floor", floor, "--candidates",
                     "200", "--json", "--force"]) == 0
        doc = json.loads(capsys.readouterr().out)
        std[model] = {p["name"]: p["std"] for p in doc["parameters"]}
    mm, m = std["puma"], std[str(path)]
    assert m["base.rx"] == pytest.approx(mm["base.rx"], rel=0.3)
    assert m["base.tx"] * 1e3 == pytest.approx(mm["base.tx"], rel=0.3)


def test_random_instrument_noise_defaults_to_mm_in_the_model_unit():
    from sim.robot.instrument import TRACKER_NOISE_RANGE_MM, random_instrument

    puma = zrp.load_model("puma")
    in_m = dataclasses.replace(puma.with_arrays(bodies=puma.bodies * 1e-3), length_unit="m")
    a = random_instrument(puma, np.random.default_rng(3))
    b = random_instrument(in_m, np.random.default_rng(3))
    lo, hi = TRACKER_NOISE_RANGE_MM
    assert lo <= a.noise_sigma <= hi  # mm
    assert b.noise_sigma == pytest.approx(a.noise_sigma * 1e-3, rel=1e-12)  # the same, in m
    np.testing.assert_allclose(np.array(b.translation) * 1e3, a.translation, rtol=1e-12)
    assert random_instrument(puma, np.random.default_rng(3), 0.5).noise_sigma == 0.5
