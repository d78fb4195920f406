"""Batched forward kinematics split across threads (zrp.kinematics._split, issue 34): the
slabs give exactly the single call's poses, and a pose out of range in any slab is refused.
No timing here (tests/benchmarks/bench_kinematics.py measures the speed)."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.errors import ZRPError
from zrp.kinematics import _kernels as K
from zrp.kinematics import _split
from zrp.kinematics._range_kernels import joint_limits
from zrp.kinematics.forward import _karrays

PUMA = zrp.load_model("puma")


def _single(q: np.ndarray) -> np.ndarray:
    out = np.empty((q.shape[0], 7))
    assert K.fk_pose_batch(q, *_karrays(PUMA), joint_limits(PUMA), out)
    return out


@pytest.mark.parametrize("threads", [2, 3])
def test_slabs_give_the_single_calls_poses(monkeypatch, threads):
    monkeypatch.setattr(_split, "n_threads", lambda: threads)
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (_split.SPLIT_MIN + 1_001, 6))  # not a multiple of a block
    p, er = zrp.end_effector_pose(PUMA, q)
    np.testing.assert_array_equal(np.hstack([p, er]), _single(q))


def test_a_pose_out_of_range_in_the_last_slab_is_refused(monkeypatch):
    monkeypatch.setattr(_split, "n_threads", lambda: 2)
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, (_split.SPLIT_MIN + 10, 6))
    zrp.end_effector_pose(PUMA, q)  # every value finite and in range: accepted
    q[-3, 2] = np.nan  # in the second slab only
    with pytest.raises(ZRPError):
        zrp.end_effector_pose(PUMA, q)


def test_small_batches_are_not_split(monkeypatch):
    calls = []

    def kernel(q, *args):
        calls.append(q.shape[0])
        return True

    monkeypatch.setattr(_split, "n_threads", lambda: 2)
    q = np.zeros((_split.SPLIT_MIN - 1, 6))
    assert _split.split_batch(kernel, q, (), np.empty((q.shape[0], 7)))
    assert calls == [q.shape[0]]
    calls.clear()
    q = np.zeros((_split.SPLIT_MIN, 6))
    assert _split.split_batch(kernel, q, (), np.empty((q.shape[0], 7)))
    assert sorted(calls) == [99_904, 100_096]  # slab edge on the kernel's 256-pose block


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="needs os.fork")
def test_a_forked_child_gets_its_own_threads(monkeypatch):
    """After a fork the parent's pool threads do not exist in the child: the child splits a
    batch with threads of its own instead of waiting on them forever."""
    import os

    monkeypatch.setattr(_split, "n_threads", lambda: 2)
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (_split.SPLIT_MIN, 6))
    zrp.end_effector_pose(PUMA, q)  # the parent's pool exists now
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            p, er = zrp.end_effector_pose(PUMA, q)
            ok = np.array_equal(np.hstack([p, er]), _single(q))
        finally:
            os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
