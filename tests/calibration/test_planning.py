"""Measurement planning (zrp.calibration.plan_poses): the predicted standard deviations agree
with the spread of identified values over repeated noisy simulations of the planned poses
(the synthetic robot of zrp.gap.data.synthetic and the diagnosis's least squares)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import PlanWarning, plan_poses
from zrp.errors import InputError
from zrp.gap import Injection, synthesize
from zrp.gap.fit.leastsq import fit, initial_registration
from zrp.gap.model.context import Context
from zrp.gap.model.effects import effect_parameters, registration_parameters

PUMA = zrp.load_model("puma")
TOOLS = ((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -70.0, 40.0))
SIGMA = 0.02
EFFECTS = ("joint_offset", "link_length")


@pytest.fixture(scope="module")
def plan():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanWarning)
        return plan_poses(PUMA, 30, EFFECTS, rng=np.random.default_rng(0), tool_points=TOOLS,
                          floor_z=-400.0, noise_sigma=SIGMA, candidates=500)


def test_plan_is_better_than_random_and_warns_about_aliases():
    with pytest.warns(PlanWarning, match="q1.offset"):
        p = plan_poses(PUMA, 30, EFFECTS, rng=np.random.default_rng(1), tool_points=TOOLS,
                       candidates=300)
    assert "q1.offset" in p.unidentifiable and "q1.offset" not in p.names
    assert p.log_det > p.log_det_random


def test_floor_keep_out(plan):
    fk = zrp.forward_kinematics(PUMA, plan.q)
    assert fk.points[..., 2].min() > -400.0 and fk.position[:, 2].min() > -400.0


def test_predicted_std_matches_repeated_identification(plan):
    inj = Injection(joint_offset={2: 1e-3, 3: -5e-4}, link={3: (0.3, 0.0, -0.2)})
    rng = np.random.default_rng(7)
    values = []
    for _ in range(60):
        meas = synthesize(PUMA, plan.q, inj, rng=rng, noise_sigma=SIGMA, tool_offsets=TOOLS)
        ctx = Context(PUMA, meas)
        reg = registration_parameters(ctx)
        specs = reg + [s for e in EFFECTS for s in effect_parameters(ctx, e)[0]
                       if s.name in plan.names]
        poses = np.arange(len(meas.pose_ids))
        th0, rb0 = initial_registration(ctx, reg, poses)
        f = fit(ctx, specs, poses, np.concatenate([th0, np.zeros(len(specs) - len(reg))]), rb0)
        assert [s.name for s in f.specs] == list(plan.names)
        values.append(f.theta)
    spread = np.std(np.array(values), axis=0, ddof=1)
    effect = [i for i, n in enumerate(plan.names) if not n.startswith(("base", "tool"))]
    ratio = spread[effect] / plan.std[effect]
    print("spread / predicted std:", np.round(ratio, 3))
    names = np.array(plan.names)[effect]
    assert np.all(np.abs(ratio - 1.0) < 0.3), dict(zip(names, ratio, strict=True))


def test_too_few_poses():
    with pytest.raises(InputError, match="n_poses"), warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanWarning)
        plan_poses(PUMA, 3, EFFECTS, rng=np.random.default_rng(0), candidates=100)
