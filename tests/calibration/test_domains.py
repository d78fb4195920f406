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
    ("q2.w_p3", "joint_compliance", "compliance"),
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
    # the lumped weights (c m g on a moment arm): the lower bound only, as compliance_payload
    assert parameter_bounds("q2.w_ee", "joint_compliance", "rad/mm") == (0.0, math.inf)
    assert "q2.w_ee = -7e-06 rad/mm is outside" in violation("compliance", "q2.w_ee", -7e-6,
                                                             "rad/mm")
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
