"""The search's backward pass drops one significance group at a time.

Two groups that stand in for one another (joint 2's offset and its encoder scale on poses where
joint 2 barely moves: the scale's basis q2 is then almost a constant) are each insignificant by
their Wald test while together they carry a real 1 mrad offset. Dropping every insignificant
group at once threw both away (the residual sum of squares grew 240-fold, back to the
registration's); the pass must drop one, refit, and keep the other."""

from __future__ import annotations

import warnings

import numpy as np

import zrp
from zrp.gap.data.synthetic import Injection, synthesize
from zrp.gap.fit.leastsq import f_test, fit, initial_registration, wald_groups
from zrp.gap.model.context import Context
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.search.greedy import SearchSettings, backward_pass
from zrp.kinematics import uniform_joint_values

ALPHA = 1e-3


def test_groups_that_stand_in_for_one_another_are_not_dropped_together():
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    limits = np.array([[-2, 2], [0.820, 0.8205], [-2, 2], [-2, 2], [-2, 2], [-2, 2]])
    q = uniform_joint_values(model, 40, rng, limits)
    meas = synthesize(model, q, Injection(joint_offset={2: 1e-3}), rng=rng)
    ctx = Context(model, meas, None)
    poses = np.arange(len(q))
    reg = registration_parameters(ctx)
    theta0, rb0 = initial_registration(ctx, reg, poses)
    extra = [s for e in ("joint_offset", "encoder_scale") for s in effect_parameters(ctx, e)[0]
             if s.name in ("q2.offset", "q2.scale")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the near-alias is the point of the test
        full = fit(ctx, reg + extra, poses, np.concatenate([theta0, np.zeros(2)]), rb0)
        registration = fit(ctx, reg, poses, theta0, rb0)
        p = wald_groups(full, len(reg))
        # the premise: each group alone insignificant, both together highly significant
        assert min(p.values()) > ALPHA and f_test(registration, full) < 1e-12
        settings = SearchSettings(poses, np.array([], dtype=int), [], rb0, ALPHA, 0.01, 4)
        final, pruned = backward_pass(ctx, full, len(reg), settings)
    assert len(pruned) == 1 and len(final.specs) == len(reg) + 1
    assert final.rss < 1.01 * full.rss  # what the pass dropped was not needed
    assert f_test(final, full) > ALPHA
