"""Faithful exports: a calibrated robot imported from a shipped URDF (example-robot-data) is
written back as that URDF patched. Checked with Pinocchio (an independent URDF parser and FK):
the same joint count nq, joint and frame names, limits and inertias, and the end link's pose
equal to the calibrated model's FK to 1e-9 mm; MuJoCo (another parser) puts every joint's
anchor and axis where the calibrated model does; FIGAROH's loader accepts the file.

Pinocchio and example-robot-data are optional (pyproject's test extras); skipped without them.
"""

from __future__ import annotations

import json
import os
import re
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tests.arms import erd_root
from zrp.calibration import CalibratedRobot, Term
from zrp.calibration.calibrated import chain
from zrp.calibration.export import export_urdf
from zrp.errors import ModelError
from zrp.gap.model.domains import ImplausibleValueError
from zrp.kinematics.forward import forward_kinematics
from zrp.model.urdf import import_urdf

#: (file under example-robot-data/robots, end link)
ROBOTS = [("ur_description/urdf/ur5_robot.urdf", "tool0"),
          ("ur_description/urdf/ur10_joint_limited_robot.urdf", "tool0"),
          ("ur_description/urdf/ur3_joint_limited_robot.urdf", "tool0"),
          ("panda_description/urdf/panda.urdf", "panda_hand"),
          ("xarm_description/urdf/xarm7.urdf", None),
          ("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
          ("z1_description/urdf/z1.urdf", "gripperStator"),
          # continuous joints; the end link is the last moving joint's child
          ("double_pendulum_description/urdf/double_pendulum_continuous.urdf", None)]


def _simulated(nominal, seed: int) -> CalibratedRobot:
    """A simulated calibration: offsets of a few mrad, axis tilts of at most 2 mrad (inside
    the physical domain), body corrections of a few tenths of a mm (not of a zero last body:
    an end link on the last joint's axis stays there)."""
    rng = np.random.default_rng(seed)
    n = nominal.n
    db = rng.normal(0.0, 0.3, (n + 1, 3))
    if not np.any(nominal.bodies[n]):
        db[n] = 0.0
    u = np.asarray(nominal.axes)
    t = rng.normal(0.0, 1e-3, (n, 3))
    t -= np.sum(t * u, axis=1, keepdims=True) * u
    t *= np.minimum(1.0, 2e-3 / np.linalg.norm(t, axis=1, keepdims=True))
    return CalibratedRobot.from_corrections(nominal, rng.normal(0.0, 3e-3, n), u + t,
                                            nominal.bodies + db)


def _pin_q(pin, pm, names, prismatic, q):
    out = pin.neutral(pm)
    for k, jn in enumerate(names):
        jm = pm.joints[pm.getJointId(jn)]
        if jm.nq == 2:   # continuous: (cos, sin)
            out[jm.idx_q:jm.idx_q + 2] = [np.cos(q[k]), np.sin(q[k])]
        else:
            out[jm.idx_q] = q[k] * (1e-3 if prismatic[k] else 1.0)
    return out


def _structure(path) -> tuple:
    """Everything but the chain's origins and axes: links (with their inertial, visual and
    collision elements), joint names, types, parents, children, limits."""
    root = ET.parse(path).getroot()
    links = tuple((el.get("name"), re.sub(r"\s+", " ", ET.tostring(el, encoding="unicode")))
                  for el in root.findall("link"))
    joints = tuple((el.get("name"), el.get("type"), el.find("parent").get("link"),
                    el.find("child").get("link"),
                    None if el.find("limit") is None else dict(el.find("limit").attrib))
                   for el in root.findall("joint"))
    return links, joints


@pytest.mark.parametrize(("rel", "end"), ROBOTS, ids=[r[0].split("/")[-1] for r in ROBOTS])
def test_exported_urdf_is_the_original_patched(rel, end, tmp_path):
    pin = pytest.importorskip("pinocchio")
    src = os.path.join(erd_root(), rel)
    imp = import_urdf(src, end_link=end)
    cal = _simulated(imp.model, seed=len(rel))
    urdf, side = export_urdf(cal, src, tmp_path / "cal.urdf", tmp_path / "cal.calibration.json",
                             end_link=end)
    assert _structure(urdf) == _structure(src)          # links, inertias, meshes, limits...
    pm0, pm = pin.buildModelFromUrdf(src), pin.buildModelFromUrdf(str(urdf))
    assert pm.nq == pm0.nq and pm.nv == pm0.nv
    assert list(pm.names) == list(pm0.names)
    assert [f.name for f in pm.frames] == [f.name for f in pm0.frames]
    assert np.array_equal(pm.lowerPositionLimit, pm0.lowerPositionLimit)
    assert np.array_equal(pm.upperPositionLimit, pm0.upperPositionLimit)
    # the masses are the original's (the inertial elements are, in their link frames, above;
    # Pinocchio's lumps links behind fixed joints, whose origins may change, into one body)
    assert [a.mass for a in pm.inertias] == [b.mass for b in pm0.inertias]
    rng = np.random.default_rng(1)
    lo = np.where(np.isfinite(cal.model.lower), cal.model.lower, -np.pi)
    hi = np.where(np.isfinite(cal.model.upper), cal.model.upper, np.pi)
    q = rng.uniform(lo, hi, (30, cal.n))
    fk = forward_kinematics(cal.model, q)
    hand = fk.rotation @ cal.model.end_effector.frame
    d, fid = pm.createData(), pm.getFrameId(imp.end_link, pin.FrameType.BODY)
    err_mm = err_rot = 0.0
    for i in range(len(q)):
        pin.framesForwardKinematics(pm, d, _pin_q(pin, pm, imp.joints, imp.model.prismatic, q[i]))
        m = d.oMf[fid]
        err_mm = max(err_mm, float(np.abs(m.translation * 1e3 - fk.position[i]).max()))
        err_rot = max(err_rot, float(np.abs(m.rotation - hand[i]).max()))
    assert err_mm < 1e-9 and err_rot < 1e-12
    # and it is not the nominal: the calibration moved the end point by about a mm
    nom = forward_kinematics(imp.model, q).position
    assert np.abs(nom - fk.position).max() > 0.1
    doc = json.loads(side.read_text())
    assert doc["urdf_file"] == "cal.urdf" and doc["chain"]["joints"] == list(imp.joints)
    assert np.allclose(doc["joint_offsets_folded"], cal.joint_offsets)


def test_mujoco_puts_the_joints_where_the_calibration_does(tmp_path):
    """MuJoCo, another URDF parser: joint anchors and axes at random q equal the calibrated
    model's joint points and axes (read as shipped, mjcf.load_shipped: the package:// meshes,
    which do not resolve beside the export, are dropped)."""
    mujoco = pytest.importorskip("mujoco")
    from mjcf import load_shipped
    src = os.path.join(erd_root(), "ur_description/urdf/ur10_joint_limited_robot.urdf")
    imp = import_urdf(src, end_link="tool0")
    cal = _simulated(imp.model, seed=3)
    urdf, _ = export_urdf(cal, src, tmp_path / "c.urdf", tmp_path / "c.json", end_link="tool0")
    mm = load_shipped(urdf)
    md = mujoco.MjData(mm)
    assert mm.nq == cal.n
    q = np.random.default_rng(2).uniform(-2.0, 2.0, (10, cal.n))
    _, _, pts, axes = chain(cal.model, q)
    for i in range(len(q)):
        for k, name in enumerate(imp.joints):
            md.qpos[mm.joint(name).qposadr[0]] = q[i, k]
        mujoco.mj_kinematics(mm, md)
        for k, name in enumerate(imp.joints):
            jid = mm.joint(name).id
            u = axes[i, k]
            assert np.abs(md.xaxis[jid] - u).max() < 1e-12
            d = md.xanchor[jid] * 1e3 - pts[i, k]      # anchor on the calibrated axis line
            assert np.linalg.norm(d - (d @ u) * u) < 1e-9


def test_figaroh_loads_the_export(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot_mod = pytest.importorskip("figaroh.tools.robot",
                                        reason="optional: pip install figaroh")
    root = erd_root()
    share = os.path.dirname(os.path.dirname(root))    # package://example-robot-data/...
    src = os.path.join(root, "ur_description/urdf/ur10_joint_limited_robot.urdf")
    imp = import_urdf(src, end_link="tool0")
    urdf, _ = export_urdf(_simulated(imp.model, 4), src, tmp_path / "c.urdf", tmp_path / "c.json",
                          end_link="tool0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = robot_mod.load_robot(str(urdf), package_dirs=share)
        robot0 = robot_mod.load_robot(src, package_dirs=share)
    assert robot.model.nq == robot0.model.nq == 6
    assert list(robot.model.names) == list(robot0.model.names)


def test_export_refuses_implausible_values(tmp_path):
    src = os.path.join(erd_root(), "ur_description/urdf/ur5_robot.urdf")
    cal = _simulated(import_urdf(src, end_link="tool0").model, 5)
    import dataclasses

    bad = dataclasses.replace(cal, terms=(Term("q3.backlash", "backlash", 3, "rad", -2e-4),))
    with pytest.raises(ImplausibleValueError, match=r"q3.backlash = -0.0002 rad"):
        export_urdf(bad, src, tmp_path / "c.urdf", tmp_path / "c.json", end_link="tool0")
    assert not list(tmp_path.iterdir())


def test_end_link_on_a_moving_joint_needs_the_end_on_its_axis(tmp_path):
    src = os.path.join(erd_root(), "ur_description/urdf/ur5_robot.urdf")
    imp = import_urdf(src)      # ends at wrist_3_link: the child of the last moving joint
    bodies = np.array(imp.model.bodies)
    bodies[-1] += [0.3, 0.0, 0.0]     # a calibrated end point off the last axis
    cal = CalibratedRobot.from_corrections(imp.model, np.zeros(imp.model.n), None, bodies)
    with pytest.raises(ModelError, match=r"wrist_3_joint.*off its axis.*end_link"):
        export_urdf(cal, src, tmp_path / "c.urdf", tmp_path / "c.json")
    # offsets alone keep the end point on the axis: that export is exact
    geo = CalibratedRobot.from_corrections(imp.model, np.full(imp.model.n, 2e-3))
    export_urdf(geo, src, tmp_path / "c.urdf", tmp_path / "c.json")


def test_cli_measurements_to_a_patched_urdf(tmp_path, capsys):
    """zrp import -> zrp calibrate -> zrp export --calibration --urdf: the patched URDF's
    Pinocchio FK is the calibrated model's."""
    pin = pytest.importorskip("pinocchio")
    from zrp.calibration import read_calibration
    from zrp.cli.app import main
    from zrp.gap import Injection, synthesize
    from zrp.kinematics import uniform_joint_values

    src = os.path.join(erd_root(), "ur_description/urdf/ur10_joint_limited_robot.urdf")
    assert main(["import", src, "--end-link", "tool0", "--out", str(tmp_path / "ur10.toml")]) == 0
    model = import_urdf(src, end_link="tool0").model
    rng = np.random.default_rng(8)
    meas = synthesize(model, uniform_joint_values(model, 60, rng),
                      Injection(joint_offset={2: 1e-3, 3: -1.5e-3}), rng=rng, frame="base",
                      noise_sigma=0.005)
    meas.to_csv(tmp_path / "d.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", str(tmp_path / "ur10.toml"), "--data",
                     str(tmp_path / "d.csv"), "--frame", "base", "--effects", "joint_offset",
                     "--out", str(tmp_path / "out")]) == 0
    comp = tmp_path / "out" / "compensation.json"
    out = tmp_path / "ur10_cal.urdf"
    capsys.readouterr()
    assert main(["export", "--calibration", str(comp), "--urdf", src, "--end-link", "tool0",
                 "--to", "urdf", "--out", str(out), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["side_file"] == str(tmp_path / "ur10_cal.calibration.json")
    cal = read_calibration(comp)
    pm = pin.buildModelFromUrdf(str(out))
    assert pm.nq == 6 and list(pm.names)[1:] == list(model.joint_names)
    d, fid = pm.createData(), pm.getFrameId("tool0", pin.FrameType.BODY)
    q = uniform_joint_values(model, 5, rng)
    fk = forward_kinematics(cal.model, q).position
    for i in range(len(q)):
        pin.framesForwardKinematics(pm, d, q[i])
        assert np.abs(d.oMf[fid].translation * 1e3 - fk[i]).max() < 1e-9
    # without --calibration, --urdf is refused by name
    assert main(["export", "--model", str(tmp_path / "ur10.toml"), "--urdf", src, "--to",
                 "urdf", "--out", str(tmp_path / "x.urdf")]) == 2
    assert "--calibration" in capsys.readouterr().err
