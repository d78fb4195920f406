"""Compensation end to end on the physics robot (sim.compensation_check): measured, not
predicted, errors of the program and of the compensated commands on fresh targets."""

from __future__ import annotations

import zrp
from sim.benchmark.scenarios import BenchmarkConfig
from sim.compensation_check import compensation_scenarios, run_compensation_check
from sim.effects import HiddenEffects


def test_compensated_targets_land_within_the_tracker_noise():
    puma = zrp.load_model("puma")
    eff = HiddenEffects(joint_offset={2: 1e-3}, joint_compliance={2: 2e-5, 3: 3e-5},
                        link_length={3: (0.3, 0.0, -0.2)}, payload=2.0)
    r = run_compensation_check(puma, eff, poses=150, n_random=24, n_circle=12, seed=0)
    assert r.compensation.residual.max() < 1e-6
    assert r.rms_before > 10 * r.noise_rms
    assert r.rms_after <= 1.5 * r.noise_rms, r.summary()


def test_compensated_column_over_benchmark_scenarios():
    rows = compensation_scenarios(zrp.load_model("puma"), BenchmarkConfig(scenarios=2, seed=0),
                                  poses=150, n_random=16, n_circle=8)
    assert [r["index"] for r in rows] == [0, 1]
    assert rows[1]["hidden"] == "cyclic_error"       # scenario 0 is thermal (not compensated)
    assert rows[1]["ratio_after_to_noise"] <= 1.5
    assert rows[1]["rms_before"] > 3 * rows[1]["rms_after"]
