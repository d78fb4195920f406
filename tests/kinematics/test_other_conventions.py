"""The conventions other libraries use, as options of the same functions (zrp.jacobian's
``rows="vw"`` and ``length_unit="m"``, end_effector_pose's ``length_unit``): checked against
Pinocchio on a URDF as shipped (UR10 of example-robot-data; skips without them) and against
the model's own results rescaled by hand on a model with a slide."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from tests.arms import erd_root
from zrp.errors import InputError
from zrp.model.urdf import import_urdf


def _ur10() -> str:
    return str(erd_root() / "ur_description/urdf/ur10_robot.urdf")


def test_vw_rows_in_metres_equal_pinocchio_local_world_aligned():
    pin = pytest.importorskip("pinocchio")
    f = _ur10()
    imp = import_urdf(f, length_unit="mm")
    m = imp.model
    pm = pin.buildModelFromUrdf(f)
    pd = pm.createData()
    rng = np.random.default_rng(1)
    for _ in range(5):
        qz = rng.uniform(-np.pi, np.pi, m.n)
        q = pin.neutral(pm)
        cols = []
        for k, jn in enumerate(imp.joints):
            jm = pm.joints[pm.getJointId(jn)]
            q[jm.idx_q] = qz[k]
            cols.append(jm.idx_v)
        pin.computeJointJacobians(pm, pd, q)
        pin.framesForwardKinematics(pm, pd, q)
        fe = pm.getFrameId(imp.end_link)
        assert np.allclose(pd.oMf[pm.getFrameId(imp.base_link)].rotation, np.eye(3))
        j_pin = pin.getFrameJacobian(pm, pd, fe, pin.LOCAL_WORLD_ALIGNED)[:, cols]
        assert np.allclose(zrp.jacobian(m, qz, rows="vw", length_unit="m"), j_pin,
                           rtol=0, atol=1e-12)
        p_m, _ = zrp.end_effector_pose(m, qz, length_unit="m")
        assert np.allclose(p_m, pd.oMf[fe].translation, rtol=0, atol=1e-12)


def test_options_rescale_the_same_result_on_a_slide():
    m = zrp.load_model("scara")  # lengths in mm, one prismatic joint
    assert m.prismatic.any()
    rng = np.random.default_rng(2)
    q = zrp.kinematics.uniform_joint_values(m, 4, rng)
    q_m = np.where(m.prismatic, q / 1000.0, q)
    J = zrp.jacobian(m, q)
    Jm = zrp.jacobian(m, q_m, length_unit="m")
    assert np.allclose(Jm[:, :3], J[:, :3], atol=1e-15)                         # rad/rad
    assert np.allclose(Jm[:, 3:], J[:, 3:] * np.where(m.prismatic, 1.0, 1e-3))  # m/rad, m/m
    assert np.allclose(zrp.jacobian(m, q, rows="vw")[:, :3], J[:, 3:])
    p, er = zrp.end_effector_pose(m, q)
    pm, erm = zrp.end_effector_pose(m, q_m, length_unit="m")
    assert np.allclose(pm, p / 1000.0) and np.allclose(erm, er)
    with pytest.raises(InputError, match="rows"):
        zrp.jacobian(m, q, rows="uv")
    with pytest.raises(InputError, match="length_unit"):
        zrp.end_effector_pose(m, q, length_unit="furlong")
