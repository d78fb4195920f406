"""mjcf.inertials: the nearest valid principal moments, and a URDF's inertials repaired on
the spec (the whole-robot cases against Pinocchio are in tests/mjcf/test_arm.py)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mjcf.inertials import I_MIN, R_BALL, kinematic_copy, nearest_valid_moments
from mjcf.shipped import load_shipped_spec

mujoco = pytest.importorskip("mujoco")


def _valid(lam) -> bool:
    return bool(min(lam) > 0 and all(a + b >= c for a, b, c in itertools.permutations(lam)))


def test_valid_moments_are_kept():
    lam = np.array([0.02, 0.03, 0.04])
    np.testing.assert_array_equal(nearest_valid_moments(lam, 2.0), lam)


def test_a_point_mass_becomes_a_small_ball():
    np.testing.assert_allclose(nearest_valid_moments(np.zeros(3), 0.2),
                               np.full(3, 0.4 * 0.2 * R_BALL**2))
    np.testing.assert_allclose(nearest_valid_moments(np.zeros(3), 0.0), np.full(3, I_MIN))


@pytest.mark.parametrize("lam", [(0.01, 0.01, 0.05), (0.05, 0.01, 0.02), (-0.01, 0.02, 0.02),
                                 (0.0, 0.0, 1.0)])
def test_invalid_moments_move_least_and_become_valid(lam):
    lam = np.array(lam)
    new = nearest_valid_moments(lam, 1.0)
    assert _valid(new)
    floored = np.maximum(lam, 0.4 * R_BALL**2)
    i = int(np.argmax(floored))
    excess = floored[i] - (floored.sum() - floored[i])
    if excess > 0:  # the projection: the largest shrinks, the others grow, by excess/3
        np.testing.assert_allclose(new - floored, np.where(np.arange(3) == i, -1, 1)
                                   * excess / 3, rtol=1e-6, atol=1e-12)
        assert new.sum() == pytest.approx(floored.sum() + excess / 3, rel=1e-6)


def test_the_repaired_inertia_compiles_in_mujoco():
    for lam in ((0.01, 0.01, 0.05), (0.0, 0.0, 0.0), (1e-3, 1e-3, 2e-3 + 1e-15)):
        new = nearest_valid_moments(np.array(lam), 1.0)
        xml = ('<mujoco><worldbody><body><inertial pos="0 0 0" mass="1" diaginertia="'
               + " ".join(f"{v:.17g}" for v in new) + '"/><joint/></body></worldbody></mujoco>')
        mujoco.MjModel.from_xml_string(xml)


def test_kinematic_copy_compiles_whatever_the_inertials(tmp_path):
    path = tmp_path / "z.urdf"
    path.write_text("<robot name='z'><link name='b'/><link name='a'><inertial><mass "
                    "value='0'/><inertia ixx='-1' iyy='0' izz='0' ixy='0' ixz='0' iyz='0'/>"
                    "</inertial></link><joint name='j' type='revolute'><parent link='b'/>"
                    "<child link='a'/><limit lower='-1' upper='1' effort='1' velocity='1'/>"
                    "</joint></robot>")
    spec = load_shipped_spec(path)
    with pytest.raises(ValueError):
        spec.compile()
    assert kinematic_copy(spec).njnt == 1
    assert float(spec.body("a").mass) == 0.0  # the spec itself untouched
