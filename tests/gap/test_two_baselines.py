"""Issue 34: two baselines, named honestly. The plain (unconstrained) complete geometric
calibration is the reference the report and diagnosis.json measure against; the physically
held one (parameters outside their domains taken out) is shown beside it when they differ,
naming the parameters that left their domain, and only it may become the final model."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.gap import Injection, diagnose, synthesize, write_outputs
from zrp.gap.report import verdict_text
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


def _quiet(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(*args, **kw)


@pytest.fixture(scope="module")
def tilted():
    """A 6 mrad axis tilt on joint 3 (parallel to joint 2: read as either) and a body error,
    diagnosed with a 2 mrad tilt domain: the plain calibration's tilt leaves its domain, the
    held one refits without it."""
    rng = np.random.default_rng(3)
    q = uniform_joint_values(PUMA, 150, rng)
    m = synthesize(PUMA, q, Injection(tilt={3: (6e-3, 0.0)}, link={4: (0.2, -0.1, 0.1)}),
                   rng=rng, noise_sigma=0.02)
    return _quiet(PUMA, m, seed=0, effects=("encoder_scale",), max_tilt_rad=2e-3)


def test_the_plain_calibration_is_the_reference_and_the_held_one_beside_it(tilted, tmp_path):
    b = tilted.assessment.baseline
    assert b.held is not None and b.outside
    assert any(w.startswith(("u2.", "u3.")) for w in b.outside)  # parallel
    # the unconstrained fit explains the tilt, the held one cannot
    assert b.withheld.rms < 0.5 * b.held.rms
    # only the held one may be final: no value outside its domain reaches the outputs
    assert tilted.final.rms <= b.model_withheld.rms == b.held.rms
    assert all(abs(p.value) <= 2e-3 for p in tilted.final_parameters
               if p.effect == "axis_misalignment")
    doc = b.to_dict()
    assert doc["rms"] == b.withheld.rms and doc["reference"] == "plain"
    held = doc["physically_held"]
    assert held["rms"] == b.held.rms and any(n.startswith(("u2.", "u3.")) for n in
                                             held["outside_domains"])
    write_outputs(tilted, tmp_path, plots=False)
    out = json.loads((tmp_path / "diagnosis.json").read_text(encoding="utf-8"))
    js = out["geometric_baseline"]
    assert js["rms"] == pytest.approx(b.withheld.rms) and js["reference"] == "plain"
    assert js["physically_held"]["rms"] == pytest.approx(b.held.rms)
    md = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "| baseline, held | the same held in the physical domains (left them: u" in md
    assert "plain least squares" in verdict_text(tilted)
    assert "held in the physical domains, which u" in verdict_text(tilted)


def test_one_baseline_when_nothing_leaves_its_domain():
    rng = np.random.default_rng(5)
    q = uniform_joint_values(PUMA, 120, rng)
    m = synthesize(PUMA, q, Injection(joint_offset={2: 1e-3}), rng=rng, noise_sigma=0.02)
    d = _quiet(PUMA, m, seed=0)
    b = d.assessment.baseline
    assert b.held is None and b.outside == () and b.model_withheld is b.withheld
    assert b.to_dict()["physically_held"] is None
    assert "held in the physical domains" not in verdict_text(d)
