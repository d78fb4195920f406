"""The blind benchmark on real arms simulated as themselves (a seeded, reduced run of
tests/benchmarks/bench_arms.py): each arm's robot has the inertias of its own shipped file,
the diagnosis gets that file as its MJCF, and the visible single effects are named right and
corrected to the target."""

from __future__ import annotations

import json

import pytest

from sim.studies.benchmark import BenchmarkConfig, run_benchmark, summary_rows
from tests.arms import shipped_arm
from zrp.cli.app import main

#: effects a geared arm shows statically; one scenario each (balanced draw), no pairs
EFFECTS = ("joint_offset", "link_length", "joint_compliance", "axis_misalignment")


def _share(cell: str) -> tuple[int, int]:
    ok, n = cell.split("(")[1].rstrip(")").split("/")
    return int(ok), int(n)


@pytest.mark.parametrize("arm", ["ur5", "panda"])
def test_reduced_blind_benchmark_on_an_arm_as_itself(arm, tmp_path):
    path, model = shipped_arm(arm)
    cfg = BenchmarkConfig(scenarios=4, seed=3, poses=60, none_fraction=0.0,
                          pair_fraction=0.0, effects=EFFECTS, arm_file=str(path))
    res = run_benchmark(model, cfg, tmp_path / "work", progress=False)
    assert res.dynamics.startswith("own inertias from") and not res.failures
    vis = {r["group"]: r for r in summary_rows(res)}["single, visible"]
    ok, n = _share(vis["named_and_corrected"])
    assert n >= 2 and ok >= 0.9 * n, vis  # the target on this arm


def test_cli_takes_the_arms_file_and_announces_a_fallback(tmp_path, capsys):
    path, model = shipped_arm("ur5")
    import zrp

    toml = zrp.save_model(model, tmp_path / "ur5.toml")
    base = ["gap-benchmark", "--model", str(toml), "--scenarios", "1", "--poses", "16",
            "--none", "1", "--pairs", "0", "--no-plots", "--no-progress", "--json"]
    assert main([*base, "--mjcf", str(path), "--out", str(tmp_path / "own")]) == 0
    own = json.loads((tmp_path / "own" / "results.json").read_text(encoding="utf-8"))
    assert own["dynamics_fallback"] is False and "ur5_robot.urdf" in own["dynamics"]
    assert own["config"]["arm_file"] == str(path)
    capsys.readouterr()
    assert main([*base, "--out", str(tmp_path / "fb")]) == 0
    fb = json.loads((tmp_path / "fb" / "results.json").read_text(encoding="utf-8"))
    assert fb["dynamics_fallback"] is True and fb["dynamics"].startswith("FALLBACK")
    assert "FALLBACK" in (tmp_path / "fb" / "summary.md").read_text(encoding="utf-8")
