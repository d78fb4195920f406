"""Batches split across threads (zrp.kinematics.parallel) give the single-threaded result to
the bit, name a joint out of range wherever it lies, and small batches stay on one thread."""

import itertools

import numpy as np
import pytest

import zrp
from zrp.errors import InputError
from zrp.kinematics.parallel import MIN_FK_POSES, MIN_JAC_POSES, _bounds, thread_count
from zrp.testing import random_arm


def _q(model, n, seed=0):
    return np.random.default_rng(seed).uniform(-3.0, 3.0, (n, model.n))


@pytest.mark.parametrize("n", [1, 255, 257, 40_003])
@pytest.mark.parametrize("threads", [2, 3])
def test_fk_split_is_bitwise_the_single_thread_result(n, threads):
    model = zrp.load_model("puma")
    q = _q(model, n)
    p1, e1 = zrp.end_effector_pose(model, q, threads=1)
    p1, e1 = p1.copy(), e1.copy()
    p2, e2 = zrp.end_effector_pose(model, q, threads=threads)
    assert np.array_equal(p1, p2) and np.array_equal(e1, e2)


def test_fk_split_with_prismatic_joints_and_a_buffer():
    arm = random_arm(np.random.default_rng(5), 6, p_prismatic=0.5)
    assert any(arm.prismatic) and not all(arm.prismatic)
    q = _q(arm, 9_001, seed=1)
    out1, out2 = np.empty((9_001, 7)), np.empty((9_001, 7))
    zrp.end_effector_pose(arm, q, out=out1, threads=1)
    zrp.end_effector_pose(arm, q, out=out2, threads=2)
    assert np.array_equal(out1, out2)


@pytest.mark.parametrize("threads", [2, 3])
def test_jacobian_split_is_bitwise_the_single_thread_result(threads):
    model = zrp.load_model("puma")
    q = _q(model, 5_003).reshape(1, 5_003, 6)
    j1 = zrp.jacobian(model, q, threads=1).copy()
    j2 = zrp.jacobian(model, q, threads=threads)
    assert j2.shape == (1, 5_003, 6, 6) and np.array_equal(j1, j2)
    assert np.array_equal(zrp.jacobian(model, q, rows="vw", length_unit="m", threads=1),
                          zrp.jacobian(model, q, rows="vw", length_unit="m", threads=2))


def test_automatic_split_equals_one_thread():
    model = zrp.load_model("puma")
    q = _q(model, MIN_FK_POSES + 300)
    p1 = zrp.end_effector_pose(model, q, threads=1)[0].copy()
    assert np.array_equal(p1, zrp.end_effector_pose(model, q)[0])
    qj = q[:MIN_JAC_POSES + 7]
    assert np.array_equal(zrp.jacobian(model, qj, threads=1).copy(), zrp.jacobian(model, qj))


@pytest.mark.parametrize("where", [10, 39_000])
def test_a_value_out_of_range_in_any_chunk_is_named(where):
    model = zrp.load_model("puma")
    q = _q(model, 40_000)
    q[where, 4] = np.nan
    for fn in (zrp.end_effector_pose, zrp.jacobian):
        with pytest.raises(InputError, match=r"joint 5 .* at index \(" + str(where) + ",\\)"):
            fn(model, q, threads=2)


def test_small_batches_stay_on_one_thread_and_bad_counts_are_refused():
    assert thread_count(MIN_FK_POSES - 1, MIN_FK_POSES, None) == 1
    assert thread_count(100, MIN_FK_POSES, 4) == 1  # one block of poses: one thread
    assert thread_count(10_000, MIN_FK_POSES, 4) == 4
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(InputError, match="threads"):
            thread_count(10, MIN_FK_POSES, bad)
    model = zrp.load_model("puma")
    with pytest.raises(InputError, match="threads"):
        zrp.end_effector_pose(model, _q(model, 10), threads=0)


@pytest.mark.parametrize(("n", "parts"), [(1, 2), (256, 2), (513, 2), (100_000, 3), (700, 5)])
def test_chunks_cover_the_batch_on_block_boundaries(n, parts):
    chunks = _bounds(n, parts)
    assert chunks[0][0] == 0 and chunks[-1][1] == n
    assert all(b == c for (_, b), (c, _) in itertools.pairwise(chunks))
    assert all(a % 256 == 0 and b > a for a, b in chunks)
