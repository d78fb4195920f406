"""URDF import (zrp.model.urdf, standard library XML) against Pinocchio on every URDF of the
example-robot-data wheel (shipped with meshes and package:// URIs), plus hand-made trees.

Pinocchio (`pin`) and example-robot-data are optional: these tests skip when they are absent
(pip install pin example-robot-data; about 140 MB, ~25 s)."""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest

import zrp
from tests.arms import erd_root
from zrp.errors import ModelFileError
from zrp.model.urdf import import_urdf, read_urdf


def _chains(tree):
    """(base, leaf) for every leaf: from the root, or below the last floating/planar joint."""
    for leaf in tree.leaves(tree.root):
        base = tree.root
        for j in tree.path(tree.root, leaf):
            if j.type in ("floating", "planar"):
                base = j.child
        yield base, leaf


def _pin_q(pm, imp, qz):
    q = __import__("pinocchio").neutral(pm)
    cols = []
    for k, jn in enumerate(imp.joints):
        jm = pm.joints[pm.getJointId(jn)]
        if jm.nq == 2:  # continuous joint: (cos, sin)
            q[jm.idx_q:jm.idx_q + 2] = [np.cos(qz[k]), np.sin(qz[k])]
        else:  # prismatic values: mm in the model, m in Pinocchio
            q[jm.idx_q] = qz[k] * (1e-3 if imp.model.prismatic[k] else 1.0)
        cols.append(jm.idx_v)
    return q, cols


@pytest.mark.slow
def test_every_example_robot_data_urdf_matches_pinocchio():
    pin = pytest.importorskip("pinocchio")
    root = erd_root()
    files = sorted(glob.glob(os.path.join(root, "*", "*", "*.urdf")))
    assert len(files) > 50
    rng = np.random.default_rng(0)
    n_chains, n_files, worst_p, worst_r, worst_j = 0, 0, 0.0, 0.0, 0.0
    for f in files:
        try:
            tree = read_urdf(f)
        except ModelFileError as exc:  # ur3.urdf is shipped as an empty <robot> element
            assert "no <link> elements" in str(exc)
            continue
        n_files += 1
        pm = pin.buildModelFromUrdf(f)
        pd = pm.createData()
        for base, leaf in _chains(tree):
            try:
                imp = import_urdf(f, base_link=base, end_link=leaf, length_unit="mm")
            except ModelFileError as exc:
                assert "mimics joint" in str(exc) or "no revolute" in str(exc), str(exc)
                continue
            m = imp.model
            n_chains += 1
            for _ in range(2):
                lo, hi = np.maximum(m.lower, -np.pi), np.minimum(m.upper, np.pi)
                qz = rng.uniform(lo, hi)
                q, cols = _pin_q(pm, imp, qz)
                pin.computeJointJacobians(pm, pd, q)
                pin.framesForwardKinematics(pm, pd, q)
                fb, fe = pm.getFrameId(base), pm.getFrameId(leaf)
                rel = pd.oMf[fb].actInv(pd.oMf[fe])
                fk = zrp.forward_kinematics(m, qz)
                worst_p = max(worst_p, np.abs(fk.position - 1e3 * rel.translation).max())
                worst_r = max(worst_r, np.abs(fk.hand_frame - rel.rotation).max())
                jw = pin.getFrameJacobian(pm, pd, fe, pin.LOCAL_WORLD_ALIGNED)[:, cols]
                rb = pd.oMf[fb].rotation.T
                jz = zrp.jacobian(m, qz)  # [omega; v_p], base frame, mm
                vs = np.where(m.prismatic, 1.0, 1e3)  # m/rad -> mm/rad; m/m stays
                worst_j = max(worst_j, np.abs(jz[:3] - rb @ jw[3:]).max() * 1e3,
                              np.abs(jz[3:] - vs * (rb @ jw[:3])).max())
    print(f"{n_files} URDFs, {n_chains} chains: |dp| {worst_p:.2e} mm, |dR| {worst_r:.2e}, "
          f"|dJ| {worst_j:.2e} mm")
    assert n_files >= 60 and n_chains >= 400
    assert worst_p < 1e-9 and worst_r < 1e-12 and worst_j < 1e-9


def test_panda_as_shipped_fixed_tool_frame_limits():
    root = erd_root()
    f = os.path.join(root, "panda_description", "urdf", "panda.urdf")
    imp = import_urdf(f, end_link="panda_hand")  # behind the fixed joint panda_hand_joint
    m = imp.model
    assert m.n == 7 and m.joint_names[0] == "panda_joint1"
    assert m.joints[3].limits == pytest.approx((-3.0718, -0.0698))
    assert m.joints[0].velocity_limit == pytest.approx(2.175)
    # limits round-trip through TOML
    back = zrp.loads_model(zrp.dumps_model(m))
    assert np.array_equal(back.lower, m.lower) and np.array_equal(back.upper, m.upper)
    assert [j.velocity_limit for j in back.joints] == [j.velocity_limit for j in m.joints]
    # the default end effector of a branching hand: an error listing the branch ends
    with pytest.raises(ModelFileError, match=r"branches.*panda_leftfinger"):
        import_urdf(f)


_TREE = """<robot name="t">
  <link name="world"/><link name="cart"/><link name="a"/><link name="b"/><link name="c"/>
  <link name="tool"/><link name="f1"/>
  <joint name="free" type="floating"><parent link="world"/><child link="cart"/></joint>
  <joint name="j1" type="continuous"><parent link="cart"/><child link="a"/>
    <origin xyz="0 0 0.1" rpy="0 0 0.3"/><axis xyz="0 0 1"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/>
    <origin xyz="0.2 0 0" rpy="0.1 0.2 0.3"/><axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.2" velocity="0.5" effort="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="b"/><child link="tool"/>
    <origin xyz="0 0 0.05" rpy="0 1.5707963267948966 0"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <joint name="finger" type="revolute"><parent link="c"/><child link="f1"/>
    <mimic joint="j3"/><limit lower="0" upper="1" velocity="1" effort="1"/></joint>
</robot>"""


def test_hand_made_tree_base_link_tool_mimic_and_floating():
    with pytest.raises(ModelFileError, match=r"'free'.*floating.*base_link='cart'"):
        import_urdf(_TREE, end_link="tool")
    imp = import_urdf(_TREE, base_link="cart", end_link="tool")
    m = imp.model
    assert m.joint_types == ("revolute", "prismatic") and m.joints[0].limits is None
    assert m.joints[1].limits == pytest.approx((-100.0, 200.0))  # m -> mm
    assert m.joints[1].velocity_limit == pytest.approx(500.0)
    assert "['finger', 'free', 'j3']" in imp.notes[0]
    with pytest.raises(ModelFileError, match="'finger' mimics joint 'j3'"):
        import_urdf(_TREE, base_link="cart", end_link="f1")
    with pytest.raises(ModelFileError, match="end_link: no link named 'nope'"):
        import_urdf(_TREE, base_link="cart", end_link="nope")
    with pytest.raises(ModelFileError, match="line 2: not valid XML"):
        import_urdf("<robot>\n<link></robot>")
