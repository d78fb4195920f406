"""The MuJoCo "real" robot: each hidden effect alone produces its physical signature, and the
measuring procedure writes what a user would get (and the truth separately)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import zrp
from sim.robot.effect_specs import parse_effects
from sim.robot.effects import HiddenEffects, motor_map, true_geometry
from sim.robot.instrument import Instrument, random_instrument
from sim.robot.measurement import (
    Procedure,
    measure,
    trajectory_poses,
    write_measurements,
    write_truth,
)
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from sim.studies.trajectories import circle_poses
from zrp.errors import InputError, OutputExistsError
from zrp.gap import load_measurements
from zrp.kinematics import reachable_poses

EXACT = Instrument(noise_sigma=0.0, rotvec=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def poses(puma):
    return reachable_poses(puma, 8, np.random.default_rng(7))


def _run(model, effects, q, rng_seed=0, procedure=None):
    robot = RealRobot(model, effects)
    return robot, measure(robot, q, EXACT, np.random.default_rng(rng_seed), procedure)


def _fk_points(model, q, tool, scale=1.0):
    m = model.with_arrays(bodies=np.asarray(model.bodies) * scale)
    fk = zrp.forward_kinematics(m, q)
    return fk.position[..., None, :] + np.einsum("...ij,mj->...mi", fk.rotation, tool)


def _truth(run, key):
    return np.asarray(run.truth["poses"][key])


def test_nominal_robot_settles_on_the_nominal_kinematics(puma, poses):
    robot, run = _run(puma, HiddenEffects(), poses)
    pts = _truth(run, "points_base_noisefree")
    expected = _fk_points(puma, poses, robot.tool_points)
    assert np.max(np.abs(pts - expected)) < 2e-4  # mm, << tracker noise (0.01 mm)
    assert np.max(np.abs(_truth(run, "q_link") - poses)) < 2e-7  # rad
    # with noise 0 and an identity instrument the CSV positions are the simulated points
    np.testing.assert_allclose(run.measurements.xyz.reshape(-1, 3, 3), pts, atol=1e-12)


def test_any_arm_with_a_prismatic_joint_settles_on_its_kinematics():
    model = zrp.load_model("stanford")
    lim = np.array([[-1.5, 1.5], [-1.5, 1.5], [0.0, 200.0], [-1.5, 1.5], [-1.5, 1.5],
                    [-1.5, 1.5]])
    q = reachable_poses(model, 4, np.random.default_rng(1), limits=lim, min_height=-1e9)
    robot, run = _run(model, HiddenEffects(link_length={3: (0.0, 0.2, 0.0)}), q)
    pts = _truth(run, "points_base_noisefree")
    geo = true_geometry(model, robot.effects)
    np.testing.assert_allclose(pts, _fk_points(geo, q, robot.tool_points), atol=3e-4)
    assert np.max(np.abs(_truth(run, "q_link")[:, 2] - q[:, 2])) < 3e-4  # mm (slide)


def test_compliance_deflection_grows_with_gravity_torque(puma):
    c = 2e-5  # rad/(N m)
    q = reachable_poses(puma, 10, np.random.default_rng(3))
    for payload in (0.0, 3.0):
        _, run = _run(puma, HiddenEffects(joint_compliance={2: c}, payload=payload), q)
        defl = _truth(run, "q_link")[:, 1] - q[:, 1]
        tau = _truth(run, "servo_torque_Nm")[:, 1]  # static torque the servo carries
        # deflection = -c tau: linear through the origin, slope -c
        slope = float(defl @ tau / (tau @ tau))
        assert slope == pytest.approx(-c, rel=0.01)
        resid = defl - slope * tau
        assert np.max(np.abs(resid)) < 0.01 * np.max(np.abs(defl))
        # larger torque, larger deflection (rank order)
        order = np.argsort(np.abs(tau))
        assert np.all(np.diff(np.abs(defl[order])) > -1e-7)
        assert np.ptp(np.abs(tau)) > 10.0  # the poses do span a range of torques
        # the other joints (integral action) stay on target
        others = np.delete(_truth(run, "q_link") - q, 1, axis=1)
        assert np.max(np.abs(others)) < 2e-7
        if payload:
            # the payload adds to the torque and so to the sag
            _, run0 = _run(puma, HiddenEffects(joint_compliance={2: c}), q)
            tau0 = _truth(run0, "servo_torque_Nm")[:, 1]
            assert not np.allclose(tau, tau0, atol=1.0)
            defl0 = _truth(run0, "q_link")[:, 1] - q[:, 1]
            np.testing.assert_allclose(defl - defl0, -c * (tau - tau0), atol=2e-6)


def _approach(robot, q, side, step=0.02):
    """Approach pose q with every joint coming from ``side`` (+1: from below)."""
    s = robot.session(q - side * 0.3)
    s.move(q - side * step, 1.0)
    s.move(q, 0.5)
    sp = s.settle()
    return s.read(sp)


def test_backlash_flips_with_approach_direction(puma):
    b = 1.0e-3  # rad of play on joint 1 (vertical axis: no gravity torque)
    robot = RealRobot(puma, HiddenEffects(backlash={1: b}))
    q = np.array([0.3, -0.4, 0.8, 0.2, 1.0, -0.5])
    up = _approach(robot, q, +1.0)
    down = _approach(robot, q, -1.0)
    lag_up = up.q_link[0] - q[0]
    lag_down = down.q_link[0] - q[0]
    # the load lags half the play behind the motor, against the direction of approach
    assert lag_up == pytest.approx(-b / 2, rel=0.05)
    assert lag_down == pytest.approx(+b / 2, rel=0.05)
    # the tool points move by the play times their distance from the axis
    r = np.linalg.norm(up.points[:, :2], axis=1)
    moved = np.linalg.norm(up.points - down.points, axis=1)
    np.testing.assert_allclose(moved, b * r, rtol=0.06)
    # joints without backlash do not care
    np.testing.assert_allclose(up.q_link[1:], q[1:], atol=2e-7)


def test_backlash_on_a_gravity_loaded_joint_rests_on_the_gravity_flank(puma):
    b = 1.0e-3
    robot = RealRobot(puma, HiddenEffects(backlash={2: b}))
    q = np.array([0.0, -0.1, 1.3, 0.0, 0.4, 0.0])
    up = _approach(robot, q, +1.0)
    down = _approach(robot, q, -1.0)
    play_up = up.q_link[1] - up.q_motor[1]
    play_down = down.q_link[1] - down.q_motor[1]
    assert abs(up.torque[1]) > 5 * robot.load_friction[1]  # gravity beats the friction
    assert play_up == pytest.approx(play_down, abs=0.02 * b)
    # the side is the one gravity pushes the load to: the servo holds against gravity, so the
    # gravity torque on the joint is -servo torque
    assert np.sign(play_up) == np.sign(-up.torque[1])
    assert abs(play_up) == pytest.approx(b / 2, rel=0.02)


def test_encoder_errors_move_the_joint_by_their_map(puma, poses):
    eff = HiddenEffects(joint_offset={3: 4e-4}, encoder_scale={5: 3e-4},
                        cyclic_error={2: (2, 3e-4, -1e-4)})
    robot, run = _run(puma, eff, poses)
    expected = motor_map(eff, poses)
    np.testing.assert_allclose(_truth(run, "q_link"), expected, atol=2e-7)
    assert expected[:, 2] - poses[:, 2] == pytest.approx(np.full(len(poses), 4e-4))
    pts = _truth(run, "points_base_noisefree")
    np.testing.assert_allclose(pts, _fk_points(puma, expected, robot.tool_points), atol=3e-4)


def test_hidden_geometry_is_the_perturbed_kinematics(puma, poses):
    eff = HiddenEffects(link_length={3: (0.3, -0.2, 0.1), 7: (0.0, 0.1, 0.2)},
                        axis_misalignment={2: (8e-4, -3e-4)})
    robot, run = _run(puma, eff, poses)
    geo = true_geometry(puma, eff)
    pts = _truth(run, "points_base_noisefree")
    np.testing.assert_allclose(pts, _fk_points(geo, poses, robot.tool_points), atol=3e-4)
    nominal = _fk_points(puma, poses, robot.tool_points)
    assert np.max(np.linalg.norm(pts - nominal, axis=-1)) > 0.2  # the error is visible
    assert np.degrees(np.arccos(np.clip(geo.axes[1] @ puma.axes[1], -1, 1))) == \
        pytest.approx(np.degrees(np.hypot(8e-4, 3e-4)), rel=1e-6)


def test_thermal_growth_scales_the_links(puma, poses):
    alpha = 2e-5
    proc = Procedure(temp_rise=15.0, temp_tau=60.0, dwell=10.0, temp_noise=0.0)
    robot, run = _run(puma, HiddenEffects(thermal_expansion=alpha), poses, procedure=proc)
    temp = _truth(run, "temperature_true")
    assert np.ptp(temp) > 5.0  # the robot warms up during the session
    pts = _truth(run, "points_base_noisefree")
    for i in range(len(poses)):
        s = 1.0 + alpha * (temp[i] - 20.0)
        np.testing.assert_allclose(pts[i], _fk_points(puma, poses[i], robot.tool_points, s),
                                   atol=3e-4)
    # the logged temperature is the true one (no sensor noise here)
    np.testing.assert_allclose(run.measurements.per_pose("temp"), np.round(temp, 3))


def test_csv_has_what_a_user_has_and_the_truth_is_separate(puma, tmp_path):
    rng = np.random.default_rng(11)
    q = reachable_poses(puma, 20, rng)
    inst = Instrument(noise_sigma=0.02)
    robot = RealRobot(puma, HiddenEffects(backlash={4: 8e-4}, payload=1.5))
    run = measure(robot, q, inst, rng)
    csv_path = write_measurements(run, tmp_path / "m.csv")
    truth_path = write_truth(run, tmp_path / "m.truth.json")
    header = csv_path.read_text().splitlines()[0].split(",")
    assert header == ["pose", "point", *[f"q{k}" for k in range(1, 7)], "x", "y", "z", "t",
                      "temp", "load", *[f"dir{k}" for k in range(1, 7)]]
    text = csv_path.read_text()
    assert "backlash" not in text and "effects" not in text
    meas = load_measurements(csv_path, puma)
    np.testing.assert_array_equal(meas.q_pose, q)
    assert meas.per_pose("load") == pytest.approx(np.full(20, 1.5))
    np.testing.assert_array_equal(meas.approach_direction(), run.direction)
    truth = json.loads(truth_path.read_text())
    assert truth["active"] == ["backlash"] and truth["effects"]["backlash"] == {"4": 8e-4}
    # the positions are in the instrument frame with the stated noise
    clean = np.asarray(truth["poses"]["points_base_noisefree"]).reshape(-1, 3)
    clean = clean @ inst.rotation.T + np.asarray(inst.translation)
    noise = meas.xyz - clean
    assert np.std(noise) == pytest.approx(0.02, rel=0.15)
    assert abs(np.mean(noise)) < 0.01
    with pytest.raises(OutputExistsError, match="--force"):
        write_measurements(run, csv_path)
    with pytest.raises(OutputExistsError, match="--force"):
        write_truth(run, truth_path)
    write_measurements(run, csv_path, deg=True, overwrite=True)
    np.testing.assert_allclose(load_measurements(csv_path, puma, deg=True).q_pose, q)


def test_order_approach_writes_no_direction_columns(puma, tmp_path):
    rng = np.random.default_rng(2)
    q = reachable_poses(puma, 10, rng)
    run = measure(RealRobot(puma), q, random_instrument(puma, rng, 0.01), rng,
                  Procedure(approach="order"))
    assert run.direction is None
    header = write_measurements(run, tmp_path / "m.csv").read_text().splitlines()[0]
    assert "dir1" not in header


def test_gravity_approach_puts_the_backlash_on_the_gravity_flank(puma):
    """Approaching against gravity, the load lags onto the flank gravity loads anyway: the
    approach direction and the gravity side then agree in every pose."""
    b = 1e-3
    rng = np.random.default_rng(4)
    q = reachable_poses(puma, 16, rng)
    run = measure(RealRobot(puma, HiddenEffects(backlash={2: b})), q, EXACT, rng,
                  Procedure(approach="gravity"))
    play = _truth(run, "q_link")[:, 1] - _truth(run, "q_motor")[:, 1]
    np.testing.assert_allclose(play, -run.direction[:, 1] * b / 2, atol=0.02 * b)
    assert 0 < np.mean(run.direction[:, 1] > 0) < 1  # both directions occur
    # joint 1 carries no gravity torque: random approach side
    assert set(np.unique(run.direction[:, 0])) == {-1.0, 1.0}


def test_jumped_transfer_settles_where_the_simulated_move_does(puma, poses):
    """The default procedure jumps to each pre-pose instead of stepping the move there; the
    slow approach and the settling decide the state, so the settled tool points agree with
    the fully simulated procedure far below the tracker noise (backlash and compliance in)."""
    eff = HiddenEffects(backlash={1: 2e-3, 2: 1e-3}, joint_compliance={3: 2e-6},
                        thermal_expansion=1.2e-5)
    runs = {}
    for mode in ("jump", "simulate"):
        robot = RealRobot(puma, eff)
        runs[mode] = measure(robot, poses, EXACT, np.random.default_rng(3),
                             Procedure(transfer=mode))
    pj = np.array(runs["jump"].truth["poses"]["points_base_noisefree"])
    ps = np.array(runs["simulate"].truth["poses"]["points_base_noisefree"])
    assert np.abs(pj - ps).max() < 1e-3  # mm; the tracker's noise is 0.01-0.03 mm
    # the clock runs as if the moves had been made: same times and temperatures to a period
    tj = runs["jump"].measurements.t
    ts = runs["simulate"].measurements.t
    assert np.abs(tj - ts).max() < 0.05
    assert runs["jump"].truth["procedure"]["transfer"] == "jump"


def test_circle_poses_follow_the_paper_circle(puma):
    q = circle_poses(puma, 24)
    p, _ = zrp.end_effector_pose(puma, q)
    setup = zrp.puma_circle()
    centre = np.asarray(setup.trajectory.center)
    assert np.linalg.norm(p - centre, axis=1) == pytest.approx(np.full(24, 125.0), abs=1e-6)
    # spread evenly round the circle: consecutive points about 2 pi r / 24 apart
    gaps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert gaps == pytest.approx(np.full(23, 2 * np.pi * 125.0 / 24), rel=0.05)
    # the robot's measurement takes the circle passed in: the same poses
    assert np.array_equal(trajectory_poses(puma, 24, setup.trajectory, setup.q0), q)
    with pytest.raises(InputError, match="trajectory"):
        trajectory_poses(puma, 24, "square", setup.q0)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="at least 8"):
        trajectory_poses(puma, 7, setup.trajectory, setup.q0)
    with pytest.raises(InputError, match="PUMA"):
        circle_poses(zrp.load_model("scara"), 24)


def test_random_poses_respect_limits_and_floor(puma):
    lim = np.tile([-1.0, 1.0], (6, 1))
    q = reachable_poses(puma, 50, np.random.default_rng(0), limits=lim, min_height=-500.0)
    assert q.shape == (50, 6) and np.all(np.abs(q) <= 1.0)
    p, _ = zrp.end_effector_pose(puma, q)
    assert np.all(p[:, 2] >= -500.0)
    with pytest.raises(InputError, match="limits"):
        reachable_poses(puma, 5, np.random.default_rng(0), limits=np.ones((6, 2)))
    with pytest.raises(InputError, match="count"):
        reachable_poses(puma, 0, np.random.default_rng(0))


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"backlash": {1: -1e-3}}, r"backlash\[1\].*> 0"),
    ({"joint_offset": {0: 1e-3}}, "1-based joint"),
    ({"joint_compliance": {2: 0.0}}, r"joint_compliance\[2\]"),
    ({"thermal_expansion": 0.5}, "thermal_expansion.*implausible"),
    ({"payload": -1.0}, "payload"),
    ({"cyclic_error": {2: (0, 1e-4, 0.0)}}, "harmonic"),
    ({"link_length": {3: (1.0, 2.0)}}, r"link_length\[3\].*3 finite"),
    ({"encoder_scale": {1: float("nan")}}, "encoder_scale"),
])
def test_hidden_effects_reject_bad_input(kwargs, match):
    with pytest.raises(InputError, match=match):
        HiddenEffects(**kwargs)


def test_bad_robot_and_procedure_options(puma):
    with pytest.raises(InputError, match=r"joints 1\.\.6"):
        RealRobot(puma, HiddenEffects(backlash={7: 1e-3}))
    with pytest.raises(InputError, match=r"bodies 1\.\.7"):
        RealRobot(puma, HiddenEffects(link_length={8: (0.0, 0.0, 1.0)}))
    with pytest.raises(InputError, match="servo_bandwidth"):
        RealRobotOptions(servo_bandwidth=-1.0)
    with pytest.raises(InputError, match="load_friction"):
        RealRobot(puma, options=RealRobotOptions(load_friction=(1.0, 2.0)))
    with pytest.raises(InputError, match="approach"):
        Procedure(approach="sideways")
    with pytest.raises(InputError, match="approach_time"):
        Procedure(approach_time=0.0)
    with pytest.raises(InputError, match="transfer"):
        Procedure(transfer="teleport")
    with pytest.raises(InputError, match="noise_sigma"):
        Instrument(noise_sigma=-0.01)
    with pytest.raises(InputError, match=r"q: expected finite joint values of shape \(P, 6\)"):
        measure(RealRobot(puma), np.zeros((3, 5)), EXACT, np.random.default_rng(0))


def test_effect_specs_of_the_command_line(puma):
    eff = parse_effects(["backlash:1=0.8mrad", "thermal_expansion=12ppm/K",
                         "link_length:4=0.1,0.2,-0.1", "cyclic_error:2:h2=0.3mrad",
                         "joint_compliance:2=20urad/Nm", "encoder_scale:3=300ppm",
                         "axis_misalignment:3=0.5,0.2mrad", "joint_offset:5=0.01deg"],
                        puma, payload=2.0)
    assert eff.backlash[1] == pytest.approx(8e-4)
    assert eff.thermal_expansion == pytest.approx(1.2e-5)
    assert eff.link_length[4] == (0.1, 0.2, -0.1)
    assert eff.cyclic_error[2] == (2, pytest.approx(3e-4), 0.0)
    assert eff.joint_compliance[2] == pytest.approx(2e-5)
    assert eff.encoder_scale[3] == pytest.approx(3e-4)
    assert eff.axis_misalignment[3] == pytest.approx((5e-4, 2e-4))
    assert eff.joint_offset[5] == pytest.approx(np.radians(0.01))
    assert eff.payload == 2.0
    assert parse_effects(["link_length:3=0,0,1um"], puma).link_length[3][2] == \
        pytest.approx(1e-3)
    for bad, match in (("backlash=1", "needs a joint"), ("wobble:1=2", "unknown effect"),
                       ("backlash:1=2furlongs", "unit"), ("thermal_expansion:2=1e-5", "no joint"),
                       ("link_length:2=1,2", "3 value"), ("backlash:1:h2=1e-3", "cyclic_error"),
                       ("nonsense", "NAME")):
        with pytest.raises(InputError, match=match):
            parse_effects([bad], puma)


def test_effects_round_trip_through_the_truth_dict():
    eff = HiddenEffects(joint_offset={2: 1e-4}, cyclic_error={3: (2, 1e-4, -2e-4)},
                        link_length={4: (0.1, 0.0, 0.2)}, thermal_expansion=1e-5, payload=1.0)
    back = HiddenEffects.from_dict(json.loads(json.dumps(eff.to_dict())))
    assert back == eff
    assert back.active == ("joint_offset", "link_length", "thermal_expansion", "cyclic_error")
    with pytest.raises(InputError, match="unknown key"):
        HiddenEffects.from_dict({"wobble": {}})
