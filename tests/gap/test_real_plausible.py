"""The real IRB 120 laser-tracker data (../shared; skipped without it): the final model is
physical, every fit converged, and it is no worse than the complete geometric calibration on
the withheld poses (issue 22)."""

from __future__ import annotations

from zrp.gap.fit.constrained import outside_domains
from zrp.gap.report import diagnosis_document


def test_final_model_is_inside_every_physical_domain(irb120_real):
    d = irb120_real.diagnosis
    assert outside_domains(d.context, d.final_fit) == []
    assert all(p.value >= 0 for p in d.final_parameters if p.effect == "backlash")
    assert not d.assessment.implausible
    # the negative plays these data ask for are named in the verdict, not used
    doc = diagnosis_document(d)
    assert any(o["effect"] == "backlash" for o in doc["identification"]["outside_domain"])


def test_no_fit_stopped_early_and_final_beats_the_geometric_calibration(irb120_real):
    d = irb120_real.diagnosis
    assert d.final_fit.converged and not d.solver_stops
    assert d.assessment.baseline.fit.converged
    assert not any("least squares" in str(w.message) for w in irb120_real.warnings)
    assert d.final.rms <= d.assessment.baseline.withheld.rms
