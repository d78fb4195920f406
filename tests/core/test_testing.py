"""The assertions of zrp.testing: they pass on equal input, in every pose form the project
uses, and fail on different input with a message naming the first element that differs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import zrp
from zrp.rotations.rodrigues import er_from_axis_angle, er_multiply, matrix_from_er
from zrp.testing import assert_manipulator_close, assert_pose_close, panda_mdh


@pytest.fixture(scope="module")
def poses(puma):
    q = zrp.uniform_joint_values(puma, 5, np.random.default_rng(0))
    return q, zrp.forward_kinematics(puma, q)


def _transforms(p, e):
    t = np.zeros((*p.shape[:-1], 4, 4))
    t[..., :3, :3] = matrix_from_er(e)
    t[..., :3, 3] = p
    t[..., 3, 3] = 1.0
    return t


def test_pose_forms_agree_with_each_other(puma, poses):
    q, fk = poses
    p, e = zrp.end_effector_pose(puma, q)
    assert_pose_close(fk, (p, e))
    assert_pose_close((p, -e), fk)                      # e and -e: the same rotation
    assert_pose_close((p, matrix_from_er(e)), (fk.position, fk.er))
    assert_pose_close(_transforms(p, e), fk, atol_rotation_rad=1e-14)
    assert_pose_close(fk, fk, atol_position=0.0, atol_rotation_rad=0.0)
    one = zrp.end_effector_pose(puma, q[0])
    assert_pose_close(one, (fk.position[0], fk.er[0]))


def test_pose_names_the_first_pose_out_of_tolerance(poses):
    _, fk = poses
    p = fk.position.copy()
    p[3, 1] += 2e-6
    p[4, 0] += 1.0
    with pytest.raises(AssertionError, match=r"pose 3: position differs by 2e-06 > "
                                             r"atol_position 1e-09 \(actual \["):
        assert_pose_close((p, fk.er), fk)
    assert_pose_close((p, fk.er), fk, atol_position=1.1)
    turned = er_multiply(fk.er, er_from_axis_angle([0.0, 0.0, 1.0], np.r_[0, 0, 3e-9, 0, 0]))
    with pytest.raises(AssertionError, match=r"pose 2: rotation differs by 3e-09 rad > "
                                             r"atol_rotation_rad 1e-12"):
        assert_pose_close((fk.position, matrix_from_er(turned)), fk, err_msg="x")
    with pytest.raises(AssertionError, match=r"^x: pose 2: rotation"):
        assert_pose_close((fk.position, turned), fk, err_msg="x")
    assert_pose_close((fk.position, turned), fk, atol_rotation_rad=4e-9)


def test_pose_refuses_what_is_not_a_pose(poses):
    _, fk = poses
    with pytest.raises(AssertionError, match="batch shapes differ"):
        assert_pose_close((fk.position[:2], fk.er[:2]), fk)
    with pytest.raises(AssertionError, match=r"actual: expected \(position"):
        assert_pose_close((fk.position, fk.er[:, :3]), fk)
    with pytest.raises(AssertionError, match="desired: expected a forward-kinematics result"):
        assert_pose_close(fk, "abc")
    nan = fk.position.copy()
    nan[0, 0] = np.nan
    with pytest.raises(AssertionError, match="pose 0: position differs by nan"):
        assert_pose_close((nan, fk.er), fk)


def test_manipulator_close_on_equal_and_round_tripped_models(puma, tmp_path):
    assert_manipulator_close(puma, puma, atol=0.0)
    back = zrp.load_model(zrp.save_model(puma, tmp_path / "p.toml"))
    assert_manipulator_close(back, puma, atol=0.0)
    assert_manipulator_close(puma.with_arrays(name="renamed"), puma)      # names: free text
    assert_manipulator_close(panda_mdh(), panda_mdh())


@pytest.mark.parametrize("change, match", [
    (lambda m: m.with_arrays(bodies=m.bodies + np.r_[0, 0, 0, 0, 1e-6, 0, 0][:, None]),
     r"^joint 5 body: \[.*\] != \[.*\] \(largest difference 1e-06 > atol 1e-12\)"),
    (lambda m: m.with_arrays(axes=np.r_[m.axes[:2], [[0.0, 0.6, 0.8]], m.axes[3:]]),
     r"^joint 3 axis: "),
    (lambda m: m.with_arrays(axial=[0.0, 1.0, 0.0], transverse=[0.0, 0.0, 1.0]),
     r"^end_effector axial: "),
    (lambda m: m.with_arrays(bodies=np.r_[m.bodies[:-1], [[1.0, 2.0, 3.0]]]),
     r"^end_effector body: "),
    (lambda m: dataclasses.replace(m, length_unit="m"), r"^length_unit: 'm' != 'mm'"),
    (lambda m: dataclasses.replace(m, joints=m.joints[:5]), r"^number of joints: 5 != 6"),
    (lambda m: dataclasses.replace(m, joints=(*m.joints[:3], dataclasses.replace(
        m.joints[3], limits=(-1.0, 1.0)), *m.joints[4:])), r"^joint 4 limits: \(-1.0, 1.0\) != "),
    (lambda m: dataclasses.replace(m, joints=(*m.joints[:1], dataclasses.replace(
        m.joints[1], type="prismatic"), *m.joints[2:])),
     r"^joint 2 type: 'prismatic' != 'revolute'"),
])
def test_manipulator_names_the_first_difference(puma, change, match):
    with pytest.raises(AssertionError, match=match):
        assert_manipulator_close(change(puma), puma)


def test_manipulator_tolerances_and_units():
    panda = panda_mdh()
    mm = panda.with_arrays(bodies=panda.bodies + 1e-9)
    with pytest.raises(AssertionError, match="joint 1 body"):
        assert_manipulator_close(mm, panda)
    assert_manipulator_close(mm, panda, atol_length=2e-9)
    assert_manipulator_close(dataclasses.replace(panda, length_unit="millimetre"), panda)
    with pytest.raises(AssertionError, match=r"b: expected a zrp\.Manipulator, got str"):
        assert_manipulator_close(panda, "panda")
