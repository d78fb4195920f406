"""mjcf.arm.load_arm on shipped URDFs as they are: the Staubli TX40 (a point-mass end link),
a whole mobile robot written here (wheels, antenna, head, torso, a 6-joint arm, fingers) read
to its flange, and a point-mass end link after a massless link; inverse dynamics against
Pinocchio's RNEA on the same URDF (the other joints locked: ``buildReducedModel``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mjcf.arm import load_arm
from zrp.errors import InputError

mujoco = pytest.importorskip("mujoco")
pin = pytest.importorskip("pinocchio")

_TX40 = Path("data") / "tx40-currents" / "tx40_mdh_modified.urdf"


def _states(n: int, rng: np.random.Generator, k: int = 12) -> tuple[np.ndarray, ...]:
    return (rng.uniform(-1.5, 1.5, (k, n)), rng.uniform(-2, 2, (k, n)),
            rng.uniform(-10, 10, (k, n)))


def _pin_q(model, names: list[str], q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration of angles ``q`` given in the order of ``names``
    (a continuous joint is (cos, sin))."""
    out = pin.neutral(model)
    for name, v in zip(names, q, strict=True):
        j = model.joints[model.getJointId(name)]
        if j.nq == 2:
            out[j.idx_q:j.idx_q + 2] = np.cos(v), np.sin(v)
        else:
            out[j.idx_q] = v
    return out


def _pin_v(model, names: list[str], v: np.ndarray) -> np.ndarray:
    out = np.zeros(model.nv)
    for name, x in zip(names, v, strict=True):
        out[model.joints[model.getJointId(name)].idx_v] = x
    return out


def _rnea(model, names: list[str], q, qd, qdd) -> np.ndarray:
    """Pinocchio's torques, in the order of ``names``."""
    data = model.createData()
    out = []
    for a, b, c in zip(q, qd, qdd, strict=True):
        tau = pin.rnea(model, data, _pin_q(model, names, a), _pin_v(model, names, b),
                       _pin_v(model, names, c))
        out.append([tau[model.joints[model.getJointId(n)].idx_v] for n in names])
    return np.array(out)


def _reduced(path: Path, keep: list[str]):
    full = pin.buildModelFromUrdf(str(path))
    lock = [full.getJointId(n) for n in full.names[1:] if n not in keep]
    return pin.buildReducedModel(full, lock, pin.neutral(full))


def test_tx40_loads_and_equals_pinocchio(shared_dir):
    path = shared_dir / _TX40
    if not path.is_file():
        pytest.skip(f"{_TX40} not in ../shared")
    arm = load_arm(path)
    assert arm.joint_names == [f"joint_{k}" for k in range(1, 7)]
    assert any("link 'link_6'" in n and "point mass" in n for n in arm.notes)
    b = mujoco.mj_name2id(arm.model, mujoco.mjtObj.mjOBJ_BODY, "link_6")
    assert arm.model.body_mass[b] == pytest.approx(0.2)  # mass and centre kept
    np.testing.assert_allclose(arm.model.body_inertia[b], 0.4 * 0.2 * 1e-8)  # a 0.1 mm ball
    pm = pin.buildModelFromUrdf(str(path))
    q, qd, qdd = _states(6, np.random.default_rng(0))
    ref = _rnea(pm, arm.joint_names, q, qd, qdd)
    tau = arm.inverse_dynamics(q, qd, qdd)
    # the ball's 8e-10 kg m^2 times link 6's angular acceleration: < 1e-6 of the torques
    err = np.abs(tau - ref).max(axis=1) / np.abs(ref).max(axis=1)
    assert err.max() < 1e-8
    np.testing.assert_allclose(tau, ref, atol=1e-7)


_INERT = '<inertial><origin xyz="{c}"/><mass value="{m}"/><inertia ixx="{i[0]}" ' \
         'iyy="{i[1]}" izz="{i[2]}" ixy="{i[3]}" ixz="0" iyz="0"/></inertial>'


def _link(name: str, m: float | None = None, c: str = "0 0 0",
          i: tuple[float, ...] = (0.01, 0.012, 0.014, 0.0)) -> str:
    body = "" if m is None else _INERT.format(c=c, m=m, i=i)
    return f'<link name="{name}">{body}</link>'


def _joint(name: str, parent: str, child: str, kind: str = "revolute", xyz: str = "0 0 0",
           axis: str = "0 0 1", extra: str = "") -> str:
    limit = ('<limit lower="-3" upper="3" effort="100" velocity="2"/>'
             if kind in ("revolute", "prismatic") else "")
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>{limit}'
            f'{extra}</joint>')


_ARM = [f"arm_joint{k}" for k in range(1, 7)]
_AXES = ["0 0 1", "0 1 0", "0 1 0", "1 0 0", "0 1 0", "1 0 0"]


def _robot(root: str = "") -> str:
    """A mobile manipulator: base with two wheels, two antennas with broken inertials, a head
    (triangle-violating inertia) on a prismatic torso, a 6-joint arm (joint 4 continuous,
    link 3 massless, a camera point mass on link 5) to a flange, a hand with two fingers."""
    links = [_link("base_footprint"), _link("base_link", 20.0, "0 0 0.1", (0.5, 0.6, 0.7, 0)),
             _link("wheel_l", 1.0), _link("wheel_r", 1.0),
             _link("antenna_a", -0.1, i=(-1e-3, 1e-3, 1e-3, 0)),
             _link("antenna_b", 0.05, i=(1e-4, 1e-4, 1e-4, 5e-4)),
             _link("torso", 8.0, "0 0 0.3", (0.2, 0.2, 0.05, 0.01)),
             _link("head", 2.0, "0.05 0 0.1", (0.001, 0.001, 0.01, 0)),
             _link("arm_link1", 3.0, "0 0 0.05"), _link("arm_link2", 2.5, "0.15 0 0"),
             _link("arm_link3", 0.0, i=(0, 0, 0, 0)), _link("arm_link4", 1.5, "0.1 0.01 0"),
             _link("arm_link5", 1.0, "0 0 0.02", (2e-3, 1e-3, 1.5e-3, 1e-4)),
             _link("camera", 0.3, "0.02 0.03 0", (0, 0, 0, 0)),
             _link("arm_link6", 0.5, "0.01 0 0.03", (5e-4, 6e-4, 7e-4, 0)),
             _link("arm_flange"), _link("hand", 0.6, "0 0 0.05", (1e-3, 1e-3, 1e-3, 0)),
             _link("finger_l", 0.05, "0 0.01 0.02", (1e-5, 1e-5, 1e-5, 0)),
             _link("finger_r", 0.05, "0 -0.01 0.02", (1e-5, 1e-5, 1e-5, 0))]
    joints = [_joint("base_fix", "base_footprint", "base_link", "fixed", "0 0 0.05"),
              _joint("wheel_l_joint", "base_link", "wheel_l", "continuous", "0 0.2 0",
                     "0 1 0"),
              _joint("wheel_r_joint", "base_link", "wheel_r", "continuous", "0 -0.2 0",
                     "0 1 0"),
              _joint("antenna_a_fix", "base_link", "antenna_a", "fixed", "-0.2 0 0.3"),
              _joint("antenna_b_fix", "base_link", "antenna_b", "fixed", "-0.2 0.1 0.3"),
              _joint("torso_lift", "base_link", "torso", "prismatic", "0 0 0.3"),
              _joint("head_pan", "torso", "head", "revolute", "0 0 0.6"),
              _joint(_ARM[0], "torso", "arm_link1", "revolute", "0.1 0 0.5", _AXES[0])]
    chain = ["arm_link1", "arm_link2", "arm_link3", "arm_link4", "arm_link5", "arm_link6"]
    offsets = ["0 0 0.1", "0.3 0 0", "0.05 0 0.02", "0.25 0 0", "0.05 0 0"]
    for k in range(1, 6):
        kind = "continuous" if k == 3 else "revolute"
        joints.append(_joint(_ARM[k], chain[k - 1], chain[k], kind, offsets[k - 1],
                             _AXES[k]))
    joints += [_joint("camera_fix", "arm_link5", "camera", "fixed", "0 0.05 0"),
               _joint("flange_fix", "arm_link6", "arm_flange", "fixed", "0.08 0 0"),
               _joint("hand_fix", "arm_flange", "hand", "fixed"),
               _joint("finger_l_joint", "hand", "finger_l", "prismatic", "0 0 0.1", "0 1 0"),
               _joint("finger_r_joint", "hand", "finger_r", "prismatic", "0 0 0.1", "0 -1 0",
                      '<mimic joint="finger_l_joint"/>')]
    return f'<robot name="mobile">{root}{"".join(links)}{"".join(joints)}</robot>'


def test_whole_robot_to_its_flange_is_the_arm_of_pinocchio(tmp_path):
    path = tmp_path / "mobile.urdf"
    path.write_text(_robot())
    arm = load_arm(path, end_link="arm_flange")
    assert arm.joint_names == ["torso_lift", *_ARM]
    assert arm.model.neq == 0
    assert list(arm.model.jnt_limited) == [1, 1, 1, 1, 0, 1, 1]  # arm_joint4 continuous
    assert arm.revolute().tolist() == [False, *[True] * 6]
    notes = "\n".join(arm.notes)
    for joint in ("wheel_l_joint", "wheel_r_joint", "head_pan", "finger_l_joint",
                  "finger_r_joint"):
        assert joint in notes  # made fixed, said
    assert "link 'antenna_a' does not move" in notes  # negative mass, off the arm: left out
    assert "link 'antenna_b' does not move" in notes  # not positive definite, off the arm
    assert "link 'head': its inertia violates the triangle inequality" in notes  # on torso
    assert "link 'camera': a point mass" in notes  # rigidly on arm_link5
    assert "link 'arm_link3' moves with joint 'arm_joint3' but has no mass" in notes
    ref_model = _reduced(path, arm.joint_names)
    q, qd, qdd = _states(arm.n, np.random.default_rng(1))
    q[:, 0] = np.abs(q[:, 0]) / 10  # the torso's lift, m
    ref = _rnea(ref_model, arm.joint_names, q, qd, qdd)
    tau = arm.inverse_dynamics(q, qd, qdd)
    err = np.abs(tau - ref).max(axis=1) / np.abs(ref).max(axis=1)
    assert err.max() < 1e-6, err


def test_a_floating_root_is_made_fixed(tmp_path):
    fixed, floating = tmp_path / "fixed.urdf", tmp_path / "floating.urdf"
    fixed.write_text(_robot())
    floating.write_text(_robot('<link name="odom"/>' + _joint(
        "odom_joint", "odom", "base_footprint", "floating")))
    a = load_arm(fixed, end_link="arm_flange")
    b = load_arm(floating, end_link="arm_flange")
    assert b.joint_names == a.joint_names
    assert any("'odom_joint'" in n and "base is fixed" in n for n in b.notes)
    q, qd, qdd = _states(a.n, np.random.default_rng(2), 4)
    np.testing.assert_allclose(b.inverse_dynamics(q, qd, qdd),
                               a.inverse_dynamics(q, qd, qdd), atol=1e-12)


_POINT_END = ("<robot name='p'>" + _link("base") + _link("l1", 2.0, "0 0 0.1")
              + _link("l2", 0.0, i=(0, 0, 0, 0)) + _link("l3", 1.0, "0.3 0 0", (0, 0, 0, 0))
              + _joint("j1", "base", "l1", xyz="0 0 0.2")
              + _joint("j2", "l1", "l2", xyz="0 0 0.3", axis="0 1 0")
              + _joint("j3", "l2", "l3", axis="1 0 0") + "</robot>")


def test_point_mass_end_after_a_massless_link_equals_pinocchio(tmp_path):
    path = tmp_path / "point.urdf"
    path.write_text(_POINT_END)
    arm = load_arm(path)
    assert arm.joint_names == ["j1", "j2", "j3"]
    assert [n.split(":")[0].split(" moves")[0] for n in arm.notes] == ["link 'l3'",
                                                                        "link 'l2'"]
    q, qd, qdd = _states(3, np.random.default_rng(3))
    ref = _rnea(pin.buildModelFromUrdf(str(path)), arm.joint_names, q, qd, qdd)
    tau = arm.inverse_dynamics(q, qd, qdd)
    err = np.abs(tau - ref).max(axis=1) / np.abs(ref).max(axis=1)
    assert err.max() < 1e-6, err


def test_a_log_with_fewer_joints_fixes_the_rest_before_the_repair(tmp_path):
    path = tmp_path / "point.urdf"
    path.write_text(_POINT_END)
    arm = load_arm(path, n_joints=2)  # l3 (a point mass) welded to the massless l2
    assert arm.joint_names == ["j1", "j2"]
    assert any("joints after link 'l2'" in n for n in arm.notes)
    assert not any("'l2' moves with joint" in n for n in arm.notes)  # l3's mass carries it
    assert any("link 'l3': a point mass" in n for n in arm.notes)


def test_a_negative_mass_on_the_arm_is_refused_by_name(tmp_path):
    path = tmp_path / "neg.urdf"
    path.write_text("<robot name='n'>" + _link("base") + _link("l1", -1.0)
                    + _joint("j1", "base", "l1") + "</robot>")
    with pytest.raises(InputError, match=r"link 'l1'.*mass -1 kg.*moves with the arm"):
        load_arm(path)
