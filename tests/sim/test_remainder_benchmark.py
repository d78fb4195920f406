"""The blind benchmark's remainder scenarios (sim/studies/benchmark/remainder.py, issue 36): the
truth never reaches the diagnosis (the proof of tests/sim/test_benchmark.py: the arguments and
the files opened while diagnosing, and the same answer without the truth files), and on the
simulated robot the diagnosis says what remains: structure and the effect's joints for gear
errors at harmonics the library lacks, and a learned term that is kept and recovers most of
the structure, its withheld RMS within 1.2x the noise (the benchmark's criterion: measured
1.15x and 1.16x with 800 poses, as with 1600; 1.22x and 1.25x before the per-component ridge of
zrp/gap/analysis/kernel.py, renders/benchmarks/bench_gap_remainder.md from
tests/benchmarks/bench_gap_remainder.py); "no structure" and no term for the effect-free and
scatter-only scenarios."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import sim.studies.benchmark.remainder as rb
from sim.studies.benchmark.blind import diagnose_blind

_OPENED: list[str] | None = None


def _audit(event: str, args: tuple) -> None:
    if _OPENED is not None and event == "open" and args and isinstance(args[0], (str, Path)):
        _OPENED.append(str(args[0]))


sys.addaudithook(_audit)


def test_truth_never_reaches_the_remainder_diagnosis(puma, tmp_path, monkeypatch):
    calls = []
    real = rb.diagnose_blind_result

    def spy(csv_path, model, **kw):
        global _OPENED
        _OPENED = []
        try:
            return real(csv_path, model, **kw)
        finally:
            calls.append((csv_path, model, kw, list(_OPENED)))
            _OPENED = None

    monkeypatch.setattr(rb, "diagnose_blind_result", spy)
    scenarios = (rb.REMAINDER_SCENARIOS[0], rb.REMAINDER_SCENARIOS[3])
    scores = rb.run_remainder_benchmark(puma, tmp_path, poses=120, scenarios=scenarios)
    assert len(calls) == 2 and len(scores) == 2
    truth_dir = (tmp_path / "truth").resolve()
    for csv_path, model, kw, opened in calls:
        assert Path(csv_path).parent.resolve() == (tmp_path / "measurements").resolve()
        assert model is puma
        assert kw == {"mjcf_path": None, "seed": kw["seed"], "residual_model": True}
        paths = {Path(p).resolve() for p in opened if Path(p).suffix in (".csv", ".json")}
        assert Path(csv_path).resolve() in paths
        assert not any(truth_dir in p.parents or p.name.endswith(".truth.json")
                       for p in paths)
    # the same answer without the truth files
    csv_path = calls[0][0]
    before = diagnose_blind(csv_path, puma, mjcf_path=None, seed=0)
    for f in truth_dir.iterdir():
        f.unlink()
    after = diagnose_blind(csv_path, puma, mjcf_path=None, seed=0)
    assert json.dumps(before, sort_keys=True, default=str) == \
        json.dumps(after, sort_keys=True, default=str)


def test_scoring_judges_both_ways():
    truth = {"instrument": {"noise_sigma": 0.02},
             "remainder_scenario": {"kind": "lacking", "joints": [2], "name": "x"}}
    noise = 3 ** 0.5 * 0.02
    found = {"remainder": {"structure": {"structured": True, "named": ["q1", "q2"],
                                         "share": 0.5, "interval": [0.4, 0.6]}},
             "residual_model": {"kept": True, "withheld_rms_physical": 3 * noise,
                                "withheld_rms_hybrid": 1.1 * noise}}
    ok = rb.score_remainder(found, truth)
    assert ok["passed"] and ok["why"] == ""
    assert ok["recovered"] == pytest.approx(1 - (1.1**2 - 1) / (3**2 - 1))
    found["residual_model"]["withheld_rms_hybrid"] = 1.3 * noise
    assert "1.30x the noise" in rb.score_remainder(found, truth)["why"]
    found["remainder"]["structure"]["named"] = ["q3"]
    assert "not all named" in rb.score_remainder(found, truth)["why"]
    truth["remainder_scenario"]["kind"] = "scatter"
    assert rb.score_remainder(found, truth)["why"] == "structure claimed; learned term kept"


@pytest.mark.slow
def test_remainder_scenarios_on_the_simulated_robot(puma, tmp_path):
    scores = rb.run_remainder_benchmark(puma, tmp_path, poses=800)
    print(*rb.remainder_table(scores, "mm")[1], sep="\n")
    for s in scores:
        if s.kind == "lacking":
            joints = {f"q{j}" for j in dict(
                (x.name, x.joints) for x in rb.REMAINDER_SCENARIOS)[s.name]}
            assert s.structured and joints <= set(s.named) and s.kept, s
            assert s.recovered >= 0.75, s  # most of what the physics leaves
        assert s.passed, (s.name, s.why)  # lacking: within 1.2x the noise (1.15x, 1.16x)
