"""The physical-domain table shared by the search and the writers (zrp.gap.model.domains)."""

from __future__ import annotations

import math

import pytest

from zrp.errors import InputError
from zrp.gap.model.domains import DOMAINS, domain_key, parameter_bounds, violation


@pytest.mark.parametrize(("name", "effect", "key"), [
    ("q3.backlash", "backlash", "backlash"),
    ("q2.compliance", "joint_compliance", "compliance"),
    ("q2.compliance_payload", "joint_compliance", "compliance"),
    ("q2.w_p3", "joint_compliance", "lumped_compliance"),
    ("q2.w_ee", "joint_compliance", "lumped_compliance"),
    ("q2.w_load", "joint_compliance", "compliance"),
    ("q6.sin2", "cyclic_error", "cyclic_amplitude"),
    ("q1.scale", "encoder_scale", "encoder_scale"),
    ("u4.t1", "axis_misalignment", "axis_tilt"),
    ("kappa", "thermal_expansion", "thermal_expansion"),
    ("q1.offset", "joint_offset", "joint_offset"),
    ("b3.x", "link_length", "link_length"),
    ("tool1.x", "registration", None),
])
def test_every_parameter_kind_has_its_domain(name, effect, key):
    assert domain_key(name, effect) == key


def test_bounds_and_units():
    assert parameter_bounds("q3.backlash", "backlash") == (0.0, DOMAINS["backlash"].upper)
    # a prismatic joint's play (mm): at most 1 mm
    assert parameter_bounds("q3.backlash", "backlash", "mm") == (0.0, 1.0)
    # compliance_payload (rad/kg) keeps the lower bound only
    assert parameter_bounds("q2.compliance_payload", "joint_compliance", "rad/kg") == (
        0.0, math.inf)
    # a lumped weight alone has no bound (a mass behind the joint); w_load (a known payload
    # at the tool) has the compliance's lower bound; the sum of a joint's weights is >= 0
    assert parameter_bounds("q2.w_ee", "joint_compliance", "rad/mm") == (-math.inf, math.inf)
    assert parameter_bounds("q2.w_load", "joint_compliance", "rad/(mm kg)") == (0.0, math.inf)
    assert "q2.w_* = -7e-06 rad/mm is outside" in violation("lumped_compliance", "q2.w_*",
                                                            -7e-6, "rad/mm")
    # each member of a grouped domain is bounded on both sides by the group's bound
    assert parameter_bounds("u2.t1", "axis_misalignment") == (-0.005, 0.005)
    assert parameter_bounds("u2.t1", "axis_misalignment", widen={"axis_tilt": 0.02}) == (
        -0.02, 0.02)
    assert parameter_bounds("q1.offset", "joint_offset") == (-0.2, 0.2)
    assert parameter_bounds("q1.offset", "joint_offset", "mm") == (-20.0, 20.0)
    assert parameter_bounds("b3.x", "link_length", "mm") == (-20.0, 20.0)
    assert parameter_bounds("tool1.x", "registration", "mm") == (-math.inf, math.inf)
    assert violation("backlash", "q1.backlash", 0.0) is None
    assert "q1.backlash = -1e-09 rad" in violation("backlash", "q1.backlash", -1e-9)
    assert violation("thermal_expansion", "kappa", -2e-4, "1/degC") is not None
    assert violation("thermal_expansion", "kappa", math.nan, "1/degC") is not None
    with pytest.raises(InputError, match="only be widened"):
        violation("axis_tilt", "u1.tilt", 0.0, widen={"axis_tilt": 1e-4})


def test_the_lumped_weights_of_a_joint_are_bounded_by_their_sum():
    """One weight may be negative (a centre of mass behind the joint, lumped on points ahead
    of it); the weights of a joint sum to its compliance times the mass it carries, >= 0."""
    from zrp.gap.model.domains import domain_violations

    names = ["q2.w_p3", "q2.w_p4", "q2.w_ee", "q3.w_p4", "q3.w_ee", "q3.w_load"]
    eff, units = ["joint_compliance"] * 6, ["rad/mm"] * 5 + ["rad/(mm kg)"]
    # q2: one negative weight, sum +6e-6: inside; q3: sum -1e-6: every q3 weight flagged
    bad = domain_violations(names, eff, units, [1e-5, -6e-6, 2e-6, 1e-6, -2e-6, 0.0])
    assert sorted(i for i, _ in bad) == [3, 4]
    assert all("the lumped weights of q3 sum to -1e-06" in why for _, why in bad)
    assert bad[0][1].startswith("q3.w_p4 = 1e-06 rad/mm")  # the search parses 'name = '
    # a negative payload weight is out by itself
    bad = domain_violations(names, eff, units, [1e-5, -6e-6, 2e-6, 1e-6, 2e-6, -1e-7])
    assert [i for i, _ in bad] == [5]


def test_a_sum_held_at_zero_is_inside_within_one_rounding():
    """Weights held at sum 0 (zrp.gap.fit.sumzero) sum to 0 up to one rounding: a sum of one
    ulp below 0 (-2e-22 with magnitudes 1e-6) is on the bound (SUM_RTOL = 4 eps of the
    magnitudes), a sum of -1e-15 (1e-9 of them) is outside."""
    from zrp.gap.model.domains import SUM_RTOL, domain_violations, sum_inside

    names, eff, units = ["q2.w_p3", "q2.w_ee"], ["joint_compliance"] * 2, ["rad/mm"] * 2
    w = [1.3e-6, -math.nextafter(1.3e-6, 1.0)]
    assert math.fsum(w) < 0 and sum_inside(w) and domain_violations(names, eff, units, w) == []
    assert -math.fsum(w) < SUM_RTOL * 2.6e-6 < 1e-15
    w = [1.3e-6, -1.3e-6 - 1e-15]
    assert not sum_inside(w) and len(domain_violations(names, eff, units, w)) == 2
    assert not sum_inside([1e-6, math.nan])
