"""The calibrated robot's joint map takes its bases from the diagnosis's one definition
(zrp.gap.model.jointbases, issue 11): every joint-correction parameter the effect builders make
has a term whose basis on the same poses is that parameter's column, MJCF and lumped-mass
compliance, backlash with and without a switching torque."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import zrp
from zrp.calibration.jointmap import NON_GEOMETRIC, Term, term_basis
from zrp.errors import InputError
from zrp.gap import Measurements
from zrp.gap.model.context import Context
from zrp.gap.model.effects import effect_parameters
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


def _context(mjcf: bool, switch: tuple[float, ...] | None) -> Context:
    rng = np.random.default_rng(3)
    P = 40
    q = uniform_joint_values(PUMA, P, rng, np.tile([-2.5, 2.5], (6, 1)))
    meas = Measurements.from_arrays(np.arange(P), q, np.zeros((P, 3)),
                                    load=rng.uniform(0.0, 3.0, P),
                                    direction=rng.choice([-1.0, 1.0], (P, 6)))
    tau = rng.normal(scale=20.0, size=(P, 6)) if mjcf else None
    return Context(PUMA, meas, tau, backlash_switch=switch)


@pytest.mark.parametrize(("mjcf", "switch"), [(True, None), (False, None),
                                              (True, (np.inf, 5.0, 5.0, np.inf, 1.0, 1.0))])
def test_every_joint_term_uses_the_diagnosis_basis(mjcf, switch):
    ctx = _context(mjcf, switch)
    count = 0
    for effect in NON_GEOMETRIC:
        specs, why = effect_parameters(ctx, effect)
        assert why is None, (effect, why)
        for s in specs:
            t = Term(s.name, effect, s.joint, s.unit, 1.0)
            np.testing.assert_array_equal(term_basis(t, ctx), s.basis[:, s.joint - 1])
            count += 1
    # offsets 6, scales 6, cyclic 24, backlash 6 and the compliance terms
    assert count > 42


def test_backlash_is_half_the_side_and_unknown_terms_are_refused():
    ctx = _context(True, None)
    b = term_basis(Term("q2.backlash", "backlash", 2, "rad", 8e-4), ctx)
    np.testing.assert_array_equal(b, -0.5 * ctx.meas.approach_direction()[:, 1])
    lead = dataclasses.replace(ctx, backlash_lead=(False, True, False, False, False, False))
    b = term_basis(Term("q2.backlash", "backlash", 2, "rad", 8e-4), lead)
    np.testing.assert_array_equal(b, 0.5 * ctx.meas.approach_direction()[:, 1])  # eq. B1
    with pytest.raises(InputError, match="backlash_lead: expected 6 flags"):
        dataclasses.replace(ctx, backlash_lead=(True,))
    with pytest.raises(InputError, match=r"q2\.sin9"):
        term_basis(Term("q2.sin9", "cyclic_error", 2, "rad", 1e-4), ctx)
    with pytest.raises(InputError, match="gravity torque"):
        term_basis(Term("q2.compliance", "joint_compliance", 2, "rad/(N m)", 1e-5),
                   _context(False, None))
