"""The fits' QR-compressed least-squares problem (zrp.gap.model.problem.compressed) and the reuse of
the identifiability check's evaluation as a fit's start (issue 15: diagnosis speed)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

import zrp
from zrp.errors import InputError
from zrp.gap.data.synthetic import Injection, synthesize
from zrp.gap.fit import leastsq
from zrp.gap.fit.leastsq import fit, identifiable_start, initial_registration
from zrp.gap.model.context import Context
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.model.problem import Evaluation, Problem, compressed
from zrp.kinematics import reachable_poses

PUMA = zrp.load_model("puma")


def test_compressed_keeps_the_normal_equations():
    rng = np.random.default_rng(3)
    J = rng.normal(size=(400, 7)) * np.array([1e-3, 1.0, 10.0, 1.0, 1e2, 1.0, 0.1])
    r = rng.normal(size=400)
    g, Jc = compressed(r, J)
    assert g.shape == (8,) and Jc.shape == (8, 7)
    np.testing.assert_allclose(np.linalg.norm(g), np.linalg.norm(r), rtol=1e-13)
    np.testing.assert_allclose(Jc.T @ Jc, J.T @ J, rtol=1e-12, atol=1e-12 * np.abs(J.T @ J).max())
    np.testing.assert_allclose(Jc.T @ g, J.T @ r, rtol=1e-10, atol=1e-10 * np.abs(J.T @ r).max())
    np.testing.assert_allclose(np.linalg.norm(Jc, axis=0), np.linalg.norm(J, axis=0),
                               rtol=1e-13)
    # the least-squares solution of the reduced problem is the original one (lstsq reference)
    np.testing.assert_allclose(np.linalg.lstsq(Jc, g, rcond=None)[0],
                               np.linalg.lstsq(J, r, rcond=None)[0], rtol=1e-10)
    assert np.allclose(Jc[-1], 0.0)  # the last row carries only the part of r outside span(J)


def _case():
    rng = np.random.default_rng(7)
    q = reachable_poses(PUMA, 40, rng)
    meas = synthesize(PUMA, q, Injection(joint_offset={2: 4e-4, 3: -3e-4},
                                         encoder_scale={5: 2e-3}), rng=rng, noise_sigma=0.01)
    ctx = Context(PUMA, meas)
    poses = np.arange(len(meas.pose_ids))
    specs = registration_parameters(ctx)
    th0, rb0 = initial_registration(ctx, specs, poses)
    return ctx, poses, specs, th0, rb0


def test_fit_equals_levenberg_marquardt_on_the_tall_jacobian():
    """On a well-posed problem (nothing held) the well-posed solver lands where scipy's
    Levenberg-Marquardt does on the tall, uncompressed problem (an independent reference), up
    to the prior's pull (eq. W4: a shift of at most a few hundredths of a standard error
    where the data pin every direction far better than the tolerances)."""
    ctx, poses, specs, th0, rb0 = _case()
    reg = fit(ctx, specs, poses, th0, rb0)
    keep, _ = leastsq.check_identifiable(ctx, reg, effect_parameters(ctx, "joint_offset")[0])
    assert keep  # the offsets the registration does not absorb
    specs = list(specs) + keep
    th0 = np.concatenate([th0, np.zeros(len(keep))])
    new = fit(ctx, specs, poses, th0, rb0)
    prob = Problem(ctx, specs, poses, rb0)
    ref = least_squares(prob.residual, th0, jac=lambda th: prob.residual_and_jacobian(th)[1],
                        method="lm", x_scale="jac", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    assert new.converged and ref.status > 0 and not new.held
    se = np.sqrt(np.diag(new.cov))
    assert np.max(np.abs(new.theta - ref.x) / se) < 0.05  # in standard errors
    np.testing.assert_allclose(new.rss, ref.fun @ ref.fun, rtol=1e-3)
    J = ref.jac
    cov = np.linalg.inv(J.T @ J) * (ref.fun @ ref.fun) / (J.shape[0] - J.shape[1])
    se_ref = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(se, se_ref, rtol=1e-3)
    np.testing.assert_allclose(new.cov / np.outer(se, se), cov / np.outer(se_ref, se_ref),
                               atol=1e-3)  # the correlations


def test_fit_from_the_identifiability_evaluation_is_the_same_fit():
    ctx, poses, specs, th0, rb0 = _case()
    reg = fit(ctx, specs, poses, th0, rb0)
    cand = effect_parameters(ctx, "encoder_scale")[0]
    keep, _, start = identifiable_start(ctx, reg, cand)
    assert keep and start.jac.shape == (start.residual.size, len(specs) + len(keep))
    theta0 = np.concatenate([reg.theta, np.zeros(len(keep))])
    plain = fit(ctx, list(specs) + keep, poses, theta0, rb0)
    reused = fit(ctx, list(specs) + keep, poses, theta0, rb0, start=start)
    np.testing.assert_allclose(reused.theta, plain.theta, rtol=1e-12, atol=1e-15)
    # a start at another point is not used: the same fit again
    other = Evaluation(start.poses, start.theta + 1.0, start.residual, start.jac)
    again = fit(ctx, list(specs) + keep, poses, theta0, rb0, start=other)
    np.testing.assert_array_equal(again.theta, plain.theta)


def test_evaluation_checks_its_shapes():
    with pytest.raises(InputError, match="Jacobian of shape"):
        Evaluation(np.arange(2), np.zeros(3), np.zeros(6), np.zeros((6, 2)))
