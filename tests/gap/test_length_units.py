"""The diagnosis of an arm described in metres is the diagnosis of the same arm in mm: every
threshold, noise estimate and result scales with the length unit (no absolute mm constants)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import zrp
from zrp.gap import Injection, diagnose, synthesize
from zrp.gap.report import verdict_text
from zrp.kinematics import reachable_poses

TOOLS_MM = np.array([[50.0, 0.0, 30.0], [-40.0, 60.0, 30.0], [0.0, -70.0, 40.0]])


def _in_metres(model: zrp.Manipulator) -> zrp.Manipulator:
    return dataclasses.replace(model.with_arrays(bodies=model.bodies * 1e-3), length_unit="m")


def _measure(model, q, inj, s):
    inj = dataclasses.replace(inj, link={k: tuple(np.array(v) * s) for k, v in inj.link.items()})
    return synthesize(model, q, inj, rng=np.random.default_rng(5), noise_sigma=0.02 * s,
                      tool_offsets=TOOLS_MM * s,
                      base_translation=np.array([1500.0, -300.0, 200.0]) * s)


def test_synthetic_gravity_torque_is_the_same_in_any_length_unit():
    """A compliance of c rad/(N m) deflects the same arm by the same angle whether it is
    described in mm or in m (the lumped masses' torque used to assume mm)."""
    puma = zrp.load_model("puma")
    q = reachable_poses(puma, 10, np.random.default_rng(1))
    inj = Injection(compliance={2: 2e-5})
    a = synthesize(puma, q, inj, rng=np.random.default_rng(0), noise_sigma=0.0,
                   tool_offsets=[[0.0, 0.0, 0.0]])
    b = synthesize(_in_metres(puma), q, inj, rng=np.random.default_rng(0), noise_sigma=0.0,
                   tool_offsets=[[0.0, 0.0, 0.0]],
                   base_translation=np.array([1500.0, -300.0, 200.0]) * 1e-3)
    plain = synthesize(puma, q, Injection(), rng=np.random.default_rng(0), noise_sigma=0.0,
                       tool_offsets=[[0.0, 0.0, 0.0]])
    assert np.max(np.abs(a.xyz - plain.xyz)) > 0.5  # mm: the sag is there (>> 1e-9)
    np.testing.assert_allclose(b.xyz * 1e3, a.xyz, atol=1e-9)


@pytest.mark.parametrize("inj", [Injection(backlash={2: 1e-3}),
                                 Injection(compliance={2: 2e-5, 3: 3e-5})],
                         ids=["backlash", "compliance"])
def test_diagnosis_in_metres_equals_the_diagnosis_in_mm(inj):
    puma = zrp.load_model("puma")
    q = reachable_poses(puma, 80, np.random.default_rng(3))
    d_mm = diagnose(puma, _measure(puma, q, inj, 1.0), seed=0)
    d_m = diagnose(_in_metres(puma), _measure(_in_metres(puma), q, inj, 1e-3), seed=0)
    assert [(s.effect, s.joints) for s in d_m.steps] == [(s.effect, s.joints)
                                                         for s in d_mm.steps]
    assert d_mm.steps  # the effect is found at all
    for attr in ("nominal", "final"):
        assert getattr(d_m, attr).rms * 1e3 == pytest.approx(getattr(d_mm, attr).rms, rel=1e-6)
    assert d_m.noise_floor.rms * 1e3 == pytest.approx(d_mm.noise_floor.rms, rel=1e-6)
    assert d_m.unexplained == d_mm.unexplained is False
    assert " m " in verdict_text(d_m) and " mm " in verdict_text(d_mm)


def test_small_arm_with_a_slide_in_metres_equals_the_same_arm_in_mm():
    """A 0.43 m Stanford-type arm: thresholds scaled by the characteristic length (a slide's
    excitation, the refusal of a wrong model) used a floor of 1 length unit, i.e. 1 m here,
    so a slide moving +-12 mm counted as unexcited in metres and excited in mm."""
    big = zrp.load_model("stanford")
    small_mm = big.with_arrays(bodies=big.bodies * 0.4)
    small_m = _in_metres(small_mm)
    assert small_m.characteristic_length == pytest.approx(small_m.reach)
    rng = np.random.default_rng(4)
    lim = np.tile([-2.0, 2.0], (6, 1))
    lim[2] = (-12.0, 12.0)
    q = reachable_poses(small_mm, 80, rng, limits=lim, min_height=-1e9)
    q_m = q.copy()
    q_m[:, 2] *= 1e-3
    inj = Injection(backlash={3: 0.1})
    d_mm = diagnose(small_mm, _measure(small_mm, q, inj, 1.0), seed=0)
    meas_m = _measure(small_m, q_m, dataclasses.replace(inj, backlash={3: 0.1e-3}), 1e-3)
    d_m = diagnose(small_m, meas_m, seed=0)
    assert [(s.effect, s.joints) for s in d_mm.steps] == [("backlash", (3,))]
    assert [(s.effect, s.joints) for s in d_m.steps] == [("backlash", (3,))]
    assert d_m.final.rms * 1e3 == pytest.approx(d_mm.final.rms, rel=1e-6)
