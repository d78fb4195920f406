"""Recycled result buffers (zrp.arrays.recycled_empty) never hand out memory still in use."""

import numpy as np

import zrp
from zrp.arrays import RECYCLE_MIN_BYTES, recycled_empty

MODEL = zrp.load_model("puma")
N = 2 * RECYCLE_MIN_BYTES // (8 * 7) + 1  # a batch large enough to be recycled


def _q(seed):
    return np.random.default_rng(seed).uniform(-2.0, 2.0, (N, 6))


def test_held_results_are_never_overwritten():
    q1, q2, q3 = _q(1), _q(2), _q(3)
    p1, e1 = zrp.end_effector_pose(MODEL, q1)
    keep = p1.copy(), e1.copy()
    p2, _ = zrp.end_effector_pose(MODEL, q2)
    only_p3, _ = zrp.end_effector_pose(MODEL, q3)  # e1's and p2's buffers are both held
    assert np.array_equal(p1, keep[0]) and np.array_equal(e1, keep[1])
    assert not np.shares_memory(only_p3, p1) and not np.shares_memory(only_p3, p2)
    ref = zrp.forward_kinematics(MODEL, q1[:100]).position  # independent NumPy path
    assert np.allclose(p1[:100], ref, atol=1e-9)


def test_a_dropped_result_is_reused_and_correct():
    a = recycled_empty((N, 7))
    ptr = a.__array_interface__["data"][0]
    del a
    b = recycled_empty((N, 7))
    assert b.__array_interface__["data"][0] == ptr
    q = _q(4)
    p, _ = zrp.end_effector_pose(MODEL, q)
    del p
    p, _ = zrp.end_effector_pose(MODEL, q[::-1].copy())
    assert np.allclose(p[:50], zrp.forward_kinematics(MODEL, q[::-1][:50]).position, atol=1e-9)


def test_jacobian_results_held_stay_intact():
    q1, q2 = _q(5)[: N // 6 + 1], _q(6)[: N // 6 + 1]
    j1 = zrp.jacobian(MODEL, q1)
    keep = j1.copy()
    zrp.jacobian(MODEL, q2)
    zrp.jacobian(MODEL, q2)
    assert np.array_equal(j1, keep)


def test_small_results_are_plain_arrays():
    a = recycled_empty((3, 7))
    b = recycled_empty((3, 7))
    assert not np.shares_memory(a, b)
