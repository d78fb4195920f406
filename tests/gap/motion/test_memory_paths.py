"""The memory-saving paths of the motion diagnosis give the values of the direct ones: the
residual evaluated block by block (a tiny block forced) against one evaluation of all samples,
the initial registration from the kinematics of the fitted poses only against the one from the
cached kinematics of every pose, and an effect's columns of the kept joints only against
those of all joints."""

from __future__ import annotations

import numpy as np
import pytest

from tests.measured import tracked_tool_point
from zrp.gap.fit.leastsq import initial_registration
from zrp.gap.model.context import Context
from zrp.gap.model.effects import registration_parameters
from zrp.gap.model.problem import Problem
from zrp.gap.motion import Trajectory, fitting
from zrp.gap.motion.effects import effect_columns
from zrp.gap.motion.fitting import Engine, named_joints
from zrp.gap.motion.paths import exercise_moves
from zrp.gap.motion.pipeline import _registration


@pytest.fixture(scope="module")
def traj(puma):
    moves = exercise_moves(np.radians([0, -20, 30, 0, 60, 0]), np.random.default_rng(7),
                           moves=3)
    t = np.arange(0, moves.duration, 5e-3)
    q = moves(t)
    xyz = tracked_tool_point(puma, moves(t - 0.003), np.random.default_rng(8))
    return Trajectory(t, q, xyz, frame="instrument")


def test_residual_in_blocks_equals_one_evaluation(puma, traj, monkeypatch) -> None:
    poses = np.arange(0, traj.n_samples, 3)
    ctx = Context(puma, traj.measurements)
    reg, reg0, rb0 = _registration(ctx, poses)
    eng = Engine(puma, traj, None, reg, rb0)
    mf = eng.fit({"sync_delay": None}, poses, reg_theta=reg0)
    every = np.arange(traj.n_samples)
    whole = Problem(mf.ctx, mf.specs, every, rb0).residual(mf.result.theta)
    monkeypatch.setattr(fitting, "RESIDUAL_BLOCK", 7)  # many blocks, a short last one
    blocks = eng.residual(mf, every)
    assert traj.n_samples % 7 != 0 and traj.n_samples > 20 * 7
    np.testing.assert_allclose(blocks, whole, rtol=1e-12, atol=1e-12 * np.abs(whole).max())
    assert np.abs(whole).max() > 1e-3  # a real residual (the delay is not modelled exactly)


def test_registration_from_the_fitted_poses_kinematics_equals_the_cached_one(puma, traj
                                                                             ) -> None:
    poses = np.arange(5, traj.n_samples, 11)
    fresh = Context(puma, traj.measurements)
    specs = registration_parameters(fresh)
    theta_sub, rb_sub = initial_registration(fresh, specs, poses)
    assert "nominal_fk" not in vars(fresh)  # the subset path: nothing cached per pose
    cached = Context(puma, traj.measurements)
    _ = cached.nominal_fk  # the cached kinematics of every pose
    theta_all, rb_all = initial_registration(cached, specs, poses)
    np.testing.assert_allclose(theta_sub, theta_all, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rb_sub, rb_all, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("effect", ["servo_lag", "reversal_friction", "dynamic_compliance",
                                    "residual_vibration"])
def test_columns_of_the_kept_joints_equal_those_of_all_joints(traj, effect) -> None:
    tau = np.random.default_rng(9).normal(0.0, 20.0, traj.q.shape)
    vals = {"q2.lag": 0.004, "q3.friction": 2e-4, "q2.dyn_compliance": 1e-5,
            "q2.dyn_omega": 60.0, "q2.dyn_zeta": 0.7, "q2.vib_gain": 0.5, "q2.vib_omega": 80.0}
    couple = {"sync.delay": 0.002, "q2.lag": 0.004}
    every = effect_columns(traj, effect, vals, tau, couple=couple)
    some = effect_columns(traj, effect, vals, tau, couple=couple,
                          joints=named_joints(["q2.x", "q3.y"]))
    want = [c for c in every if c.joint in (2, 3) or c.via.startswith(("q2.", "q3."))]
    assert len(some) == len(want) < len(every)
    for a, b in zip(some, want, strict=True):
        assert (a.name, a.via) == (b.name, b.via)
        np.testing.assert_array_equal(np.asarray(a.d), np.asarray(b.d))
        np.testing.assert_array_equal(np.asarray(a.D), np.asarray(b.D))


def test_named_joints() -> None:
    assert named_joints(["q2.lag", "q12.vib_gain"]) == {2, 12}
    assert named_joints(["q2.lag", "sync.delay"]) is None
    assert named_joints(None) is None
    assert named_joints([]) == frozenset()
