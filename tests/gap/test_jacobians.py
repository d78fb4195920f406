"""Analytic identification Jacobians of every effect against central finite differences."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.gap.data.measurements import Measurements
from zrp.gap.model.context import EFFECTS, Context
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.model.problem import Problem
from zrp.gap.search.lookalike import SCALE
from zrp.kinematics.identification import parameter_jacobian
from zrp.rotations import matrix_from_rotvec


def _data(model, rng, frame="instrument", poses=12, points=2):
    n = model.n
    q = rng.uniform(-2.0, 2.0, (poses, n))
    pose = np.repeat(np.arange(poses), points)
    point = np.tile([f"s{j}" for j in range(points)], poses)
    temp = np.repeat(rng.uniform(18.0, 26.0, poses), points)
    load = np.repeat(rng.uniform(0.0, 3.0, poses), points)
    xyz = rng.normal(size=(poses * points, 3)) * 100.0
    return Measurements.from_arrays(pose, np.repeat(q, points, axis=0), xyz, point=point,
                                    frame=frame, temp=temp, load=load)


def _fd(problem, theta, h=1e-6):
    J = np.empty((problem.n_residuals, theta.size))
    for i in range(theta.size):
        e = np.zeros_like(theta)
        e[i] = h
        J[:, i] = (problem.residual(theta + e) - problem.residual(theta - e)) / (2 * h)
    return J


@pytest.mark.parametrize("name", ["puma", "stanford"])
@pytest.mark.parametrize("effect", EFFECTS)
def test_effect_jacobian_matches_finite_differences(name, effect):
    rng = np.random.default_rng(11)
    model = zrp.load_model(name)
    meas = _data(model, rng)
    ctx = Context(model, meas)
    specs, why = effect_parameters(ctx, effect)
    assert specs, why
    specs = registration_parameters(ctx) + specs
    prob = Problem(ctx, specs, np.arange(len(meas.pose_ids)),
                   base_rotation=matrix_from_rotvec([0.3, -0.2, 1.0]))
    # a generic, non-zero parameter point (exactness away from zero matters for the solver)
    theta = rng.normal(size=len(specs)) * 1e-2
    for i, s in enumerate(specs):
        if s.unit == prob.ctx.model.length_unit:
            theta[i] = rng.normal() * 5.0
    _, J = prob.residual_and_jacobian(theta)
    Jfd = _fd(prob, theta)
    scale = np.abs(Jfd).max(axis=0) + 1e-9
    err = np.abs(J - Jfd).max(axis=0) / scale
    assert err.max() < 1e-5, [s.name for s, e in zip(specs, err, strict=False) if e >= 1e-5]


@pytest.mark.parametrize("name", ["puma", "stanford"])
def test_thermal_with_its_lookalike_scale_matches_finite_differences(name):
    """kappa and a common scale of the links in one model (the look-alike test of
    zrp.gap.search.lookalike): two ``thermal`` parameters whose scales add per pose."""
    rng = np.random.default_rng(12)
    model = zrp.load_model(name)
    meas = _data(model, rng)
    ctx = Context(model, meas)
    kappa, _ = effect_parameters(ctx, "thermal_expansion")
    specs = registration_parameters(ctx) + kappa + [SCALE]
    prob = Problem(ctx, specs, np.arange(len(meas.pose_ids)),
                   base_rotation=matrix_from_rotvec([0.3, -0.2, 1.0]))
    theta = rng.normal(size=len(specs)) * 1e-2
    _, J = prob.residual_and_jacobian(theta)
    Jfd = _fd(prob, theta)
    err = np.abs(J - Jfd).max(axis=0) / (np.abs(Jfd).max(axis=0) + 1e-9)
    assert err.max() < 1e-5
    # the scale is kappa's column with 1 in place of dT (up to the other's scale factor)
    i_k, i_s = len(specs) - 2, len(specs) - 1
    theta[[i_k, i_s]] = 0.0
    _, J0 = prob.residual_and_jacobian(theta)
    dT = np.repeat(ctx.dtemp, 2)[:, None] * np.ones((1, 3))
    assert np.allclose(J0[:, i_k].reshape(-1, 3), dT * J0[:, i_s].reshape(-1, 3))


def test_geometric_columns_agree_with_identification_module():
    """At theta = 0 (flange point, no tool offset, base frame) the link and tilt columns equal
    the position rows of zrp.kinematics.identification.parameter_jacobian."""
    rng = np.random.default_rng(3)
    model = zrp.load_model("puma")
    meas = _data(model, rng, frame="base", poses=5, points=1)
    ctx = Context(model, meas)
    specs = (effect_parameters(ctx, "link_length")[0]
             + effect_parameters(ctx, "axis_misalignment")[0]
             + effect_parameters(ctx, "joint_offset")[0])
    prob = Problem(ctx, specs, np.arange(5))
    _, J = prob.residual_and_jacobian(np.zeros(len(specs)))
    ref = parameter_jacobian(model, meas.q_pose, joint_offsets=True)[:, 3:6, :]
    np.testing.assert_allclose(J.reshape(5, 3, -1), ref, atol=1e-9)


def test_the_chain_is_kept_for_its_theta_only_and_read_only():
    """A Problem hands out its last chain again for the same theta (the full-pose fit asks
    twice), a new one for any other theta, and the kept arrays cannot be written."""
    model = zrp.load_model("puma")
    ctx = Context(model, _data(model, np.random.default_rng(3)))
    specs = registration_parameters(ctx) + effect_parameters(ctx, "joint_offset")[0]
    prob = Problem(ctx, specs, np.arange(12))
    theta = np.random.default_rng(4).normal(size=len(specs)) * 1e-3
    ch = prob._chain(theta)
    assert prob._chain(theta.copy()) is ch
    other = theta.copy()
    other[-1] += 1e-12
    assert prob._chain(other) is not ch
    with pytest.raises(ValueError, match="read-only"):
        ch.pos[0, 0] = 1.0
    r1, _ = prob.residual_and_jacobian(theta)
    prob._last = None  # the same values computed afresh
    assert np.array_equal(r1, prob.residual_and_jacobian(theta)[0])


def test_the_moment_arms_are_computed_once_per_context():
    model = zrp.load_model("puma")
    ctx = Context(model, _data(model, np.random.default_rng(5)))
    labels, h = ctx.moment_arms()
    labels2, h2 = ctx.moment_arms()
    assert h2 is h and labels2 == labels
    labels2.append("x")  # the caller's list, not the cache's
    assert ctx.moment_arms()[0] == labels
    with pytest.raises(ValueError, match="read-only"):
        h[0, 0, 0] = 1.0
