"""The single-pose fast paths of end_effector_pose and jacobian (one packed kernel call) give
what the batched kernels and the NumPy reference give, and refuse what they refuse."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.errors import InputError


@pytest.mark.parametrize("name", ["puma", "stanford", "scara"])
def test_single_pose_equals_batched_and_numpy(name):
    model = zrp.load_model(name)
    rng = np.random.default_rng(2)
    qs = rng.uniform(-2, 2, (20, model.n))
    p_b, e_b = zrp.end_effector_pose(model, qs)
    j_b = zrp.jacobian(model, qs)
    ref = zrp.forward_kinematics(model, qs)
    singles = [zrp.end_effector_pose(model, q) for q in qs]
    assert all(p.shape == (3,) and e.shape == (4,) for p, e in singles)
    one = tuple(np.array(x) for x in zip(*singles, strict=True))
    zrp.testing.assert_pose_close(one, (p_b, e_b), atol_position=1e-12, atol_rotation_rad=4e-15)
    zrp.testing.assert_pose_close(one, ref, atol_position=1e-9, atol_rotation_rad=4e-12)
    for i, q in enumerate(qs):
        j = zrp.jacobian(model, q)
        assert j.shape == (6, model.n)
        np.testing.assert_allclose(j, j_b[i], rtol=0, atol=1e-12)
    # a strided 1-D view is taken as is
    wide = np.zeros((model.n, 2))
    wide[:, 0] = qs[0]
    np.testing.assert_allclose(zrp.end_effector_pose(model, wide[:, 0])[0], p_b[0], atol=1e-12)


def test_single_pose_refuses_like_the_general_path():
    model = zrp.load_model("puma")
    q = np.array([0.1, 0.2, np.nan, 0.4, 0.5, 0.6])
    with pytest.raises(InputError, match="joint 3"):
        zrp.end_effector_pose(model, q)
    with pytest.raises(InputError, match="joint 3"):
        zrp.jacobian(model, q)
    with pytest.raises(InputError, match="shape"):
        zrp.end_effector_pose(model, np.zeros(5))
    with pytest.raises(InputError, match="shape"):
        zrp.jacobian(model, np.zeros(7))
