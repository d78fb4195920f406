"""Compensation end to end on the physics robot (sim.studies.compensation_check): measured, not
predicted, errors of the program and of the compensated commands on fresh targets."""

from __future__ import annotations

import zrp
from sim.robot.effects import HiddenEffects
from sim.studies.benchmark import render_text, run_benchmark, write_outputs
from sim.studies.benchmark.report import compensated_summary
from sim.studies.benchmark.scenarios import BenchmarkConfig
from sim.studies.compensation_check import run_compensation_check


def test_compensated_targets_land_within_the_tracker_noise():
    puma = zrp.load_model("puma")
    eff = HiddenEffects(joint_offset={2: 1e-3}, joint_compliance={2: 2e-5, 3: 3e-5},
                        link_length={3: (0.3, 0.0, -0.2)}, payload=2.0)
    r = run_compensation_check(puma, eff, poses=150, n_random=24, n_circle=12, seed=0)
    assert r.compensation.residual.max() < 1e-6
    assert r.rms_before > 10 * r.noise_rms
    assert r.rms_after <= 1.5 * r.noise_rms, r.summary()


def test_blind_benchmark_report_carries_the_compensated_column(tmp_path):
    cfg = BenchmarkConfig(scenarios=2, seed=0, poses=120, compensate=16)
    res = run_benchmark(zrp.load_model("puma"), cfg, tmp_path / "work", progress=False)
    s = {x.index: x for x in res.scores}
    assert s[1].hidden == ("cyclic_error",)       # scenario 0 is thermal expansion
    for x in res.scores:
        assert x.values["comp_targets"] == 24 and x.values["comp_predicted_max"] < 1e-6
    assert s[1].values["comp_ratio_before"] > 3.0
    assert s[1].values["comp_ratio"] <= 1.5
    assert s[0].values["comp_ratio"] <= 1.5       # thermal: at the logged temperatures
    text = render_text(res)
    assert "## Compensated" in text and compensated_summary(res) in text
    files = write_outputs(res, tmp_path / "out", plots=False)
    header = next(f for f in files if f.name == "scenarios.csv").read_text().splitlines()[0]
    assert header.endswith("comp_ratio_before,comp_ratio")
