"""sim.dynamics.load_arm reads a shipped URDF through mjcf.load_shipped_spec: the Panda of
example-robot-data, its fingers fixed by ``end_link``, against Pinocchio's RNEA on the whole
URDF (fingers at rest), and a toy URDF's mimic finger."""

from __future__ import annotations

import numpy as np
import pytest

from mjcf.arm import load_arm
from mjcf.inverse import gravity_torques
from tests.arms import SHIPPED_URDFS, erd_root
from zrp.errors import InputError

mujoco = pytest.importorskip("mujoco")


def test_panda_to_link8_has_the_urdfs_gravity_torques():
    pin = pytest.importorskip("pinocchio")
    path = erd_root() / SHIPPED_URDFS["panda"][0]
    arm = load_arm(path, end_link="panda_link8")
    assert arm.n == 7 and arm.model.neq == 0
    assert arm.joint_names == [f"panda_joint{k}" for k in range(1, 8)]
    assert len(arm.moving_bodies()) == 7  # link8, the hand and the fingers fused into link7
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.5, 1.5, (5, 7))
    tau = gravity_torques(arm.model, q)
    for qi, ti in zip(q, tau, strict=True):
        full = np.concatenate([qi, np.zeros(pm.nq - 7)])  # fingers closed
        ref = pin.rnea(pm, pd, full, np.zeros(pm.nv), np.zeros(pm.nv))[:7]
        np.testing.assert_allclose(ti, ref, atol=1e-6)


_TOY = """<robot name="toy">
  <link name="base"/>
  <link name="arm"><inertial><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <link name="finger_a"><inertial><origin xyz="0 0 0.1"/><mass value="0.1"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <link name="finger_b"><inertial><origin xyz="0 0 0.1"/><mass value="0.1"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="1"/></joint>
  <joint name="fa" type="prismatic"><parent link="arm"/><child link="finger_a"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.04" effort="10" velocity="1"/></joint>
  <joint name="fb" type="prismatic"><parent link="arm"/><child link="finger_b"/>
    <axis xyz="-1 0 0"/><limit lower="0" upper="0.04" effort="10" velocity="1"/>
    <mimic joint="fa"/></joint>
</robot>"""


def test_end_link_fixes_the_fingers_and_their_mimic(tmp_path):
    path = tmp_path / "toy.urdf"
    path.write_text(_TOY)
    arm = load_arm(path, end_link="arm")
    assert arm.n == 1 and arm.model.neq == 0
    assert arm.model.body_mass[arm.tool_body] == pytest.approx(2.2)  # fingers fused
    with pytest.raises(InputError, match="end_link: no link"):
        load_arm(path, end_link="hand")
