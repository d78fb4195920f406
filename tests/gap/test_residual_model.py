"""The learned residual term (zrp/gap/analysis/residual.py, ``residual_model=True``): on an arm
with an unmodelled smooth sag or a gear error at a harmonic the library lacks
(zrp/gap/data/synthetic.py) it lowers the withheld error to within 1.2x the noise (3-D RMS of
pure noise: sqrt(3) sigma) and is kept; on pose-to-pose scatter the test of what remains finds no
structure and the term is not kept. Either way the final model stays the physical one, its
effects named."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from zrp.gap import Injection, Measurements, diagnose, synthesize
from zrp.gap.report import diagnosis_document, verdict_text
from zrp.kinematics import uniform_joint_values

from .test_recovery import IRB120, LIMITS

SIGMA = 0.02  # mm per coordinate


def _measure(injection, seed, poses, scatter=0.0):
    rng = np.random.default_rng(seed)
    q = uniform_joint_values(IRB120, poses, rng, LIMITS["irb120"])
    meas = synthesize(IRB120, q, injection, rng=rng, noise_sigma=SIGMA)
    if scatter:  # a shift of the whole tool per pose that no joint angle predicts
        shift = np.repeat(rng.normal(scale=scatter, size=(poses, 3)), 3, axis=0)
        meas = Measurements.from_arrays(meas.pose, meas.q, meas.xyz + shift, point=meas.point)
    return meas


def _diagnose(meas, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(IRB120, meas, seed=0, **kw)


@pytest.mark.slow
def test_learned_term_recovers_the_sag_and_leaves_the_physics_named():
    meas = _measure(Injection(sag=0.15), seed=11, poses=800)
    plain = _diagnose(meas)
    d = _diagnose(meas, residual_model=True)
    rm = d.assessment.residual_model
    noise = np.sqrt(3) * SIGMA
    assert plain.assessment.residual_model is None
    assert rm is not None and rm.kept
    assert rm.withheld_rms_physical == pytest.approx(d.final.rms)
    assert rm.withheld_rms_physical > 1.3 * noise  # the physics alone leaves the sag
    assert rm.withheld_rms_hybrid <= 1.2 * noise
    # the final model is the physical one, unchanged by the learned term
    assert d.effects == plain.effects and d.final.rms == plain.final.rms
    assert "kept: it lowers the withheld error clearly" in verdict_text(d)
    doc = diagnosis_document(d)
    ranges = doc["residual_model"]["training_ranges"]
    assert set(ranges) >= {"q2", "q3"} and ranges["q2"][0] < ranges["q2"][1]


def test_learned_term_recovers_a_gear_error_the_library_lacks():
    """A 3rd-harmonic gear error of joint 2 (the library's cyclic error has harmonics 1 and 2),
    800 poses: the physics leaves 2.6x the noise, the learned term 1.16x. Measured on seeds
    21-25: 1.09x-1.19x (with one ridge for all targets, before the per-component ridge of
    zrp/gap/analysis/kernel.py: 1.13x-1.22x, one of the five above the bar)."""
    d = _diagnose(_measure(Injection(cyclic_error={2: (3, 0.4e-3, 0.15e-3)}), seed=21,
                           poses=800), residual_model=True)
    s, rm = d.assessment.remainder.structure, d.assessment.residual_model
    noise = np.sqrt(3) * SIGMA
    assert s is not None and s.structured and "q2" in s.named
    assert rm is not None and rm.kept and rm.structured
    assert rm.withheld_rms_physical > 2 * noise  # the physics alone leaves the gear error
    assert rm.withheld_rms_hybrid <= 1.2 * noise, rm.withheld_rms_hybrid / noise


@pytest.mark.parametrize("scatter", [0.0, 0.05])
def test_learned_term_on_scatter_is_not_kept(scatter):
    d = _diagnose(_measure(Injection(), seed=12, poses=300, scatter=scatter),
                  residual_model=True)
    s, rm = d.assessment.remainder.structure, d.assessment.residual_model
    assert s is not None and not s.structured
    assert rm is not None and not rm.kept and not rm.structured
    assert "not kept: the test of what remains finds no structure" in verdict_text(d)
    assert diagnosis_document(d)["residual_model"]["structured"] is False


def test_residual_model_option_is_checked():
    from zrp.errors import InputError
    from zrp.gap import DiagnosisOptions
    with pytest.raises(InputError, match="residual_model"):
        DiagnosisOptions(residual_model="yes")


@pytest.mark.slow
def test_real_irb120_has_no_structure_and_keeps_its_final_model(irb120_real):
    """The shared IRB 120 (skipped without ../shared): what remains is pose-to-pose scatter to
    the multivariate test, the learned term is not kept, and the final model is unchanged."""
    plain = irb120_real.diagnosis
    s = plain.assessment.remainder.structure
    assert s is not None and not s.structured and "No structure" in verdict_text(plain)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(irb120_real.model, irb120_real.measurements, seed=0, residual_model=True)
    assert not d.assessment.residual_model.kept
    assert d.effects == plain.effects and d.final.rms == plain.final.rms
    assert d.final_joints == plain.final_joints
