"""The K-planned-poses study (sim/studies/planning.py, ``zrp plan-benchmark``): its machinery
at a small size (the full study is in zrp/calibration/README.md)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from sim.studies.planning import DesignScore, design_rows, smallest_matching_k
from zrp.calibration import design_std, plan_poses
from zrp.cli.app import main
from zrp.errors import InputError

PUMA = zrp.load_model("puma")


def _score(scn, design, poses, ok, std):
    return DesignScore(scn, ("cyclic_error",), design, poses, ("cyclic_error",),
                       ("cyclic_error",) if ok else ("none",), ok, ok, 0.03,
                       0.03 if ok else 0.1, 1.0 if ok else 3.3, ok, std, 0.0)


def test_design_rows_and_the_smallest_matching_k():
    ref = {"a": 1.0, "b": 2.0}
    scores = [_score(0, "random", 200, True, ref), _score(1, "random", 200, True, ref),
              _score(0, "planned", 20, False, {"a": 3.0, "b": 4.0}),
              _score(1, "planned", 20, True, {"a": 3.0, "b": 4.0}),
              _score(0, "planned", 30, True, {"a": 2.0, "b": 2.0}),
              _score(1, "planned", 30, True, {"a": 2.0, "b": 2.0})]
    rows = design_rows(scores)
    assert [(r["design"], r["poses"], r["success"]) for r in rows] == [
        ("random", 200, 2), ("planned", 20, 1), ("planned", 30, 2)]
    assert rows[1]["std_ratio_median"] == pytest.approx(2.5)      # median(3/1, 4/2)
    assert rows[1]["std_ratio_worst"] == pytest.approx(3.0)
    assert smallest_matching_k(scores) == 30
    assert smallest_matching_k(scores[:3]) is None
    with pytest.raises(InputError, match="design"):
        _score(0, "clever", 20, True, ref)


def test_design_std_of_a_plan_is_the_plans_prediction():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_poses(PUMA, 25, ["joint_offset", "backlash"],
                          rng=np.random.default_rng(0), candidates=300)
        names, std = design_std(PUMA, plan.q, plan.direction, ["joint_offset", "backlash"])
    assert names == plan.names
    np.testing.assert_allclose(std, plan.std, rtol=1e-8)


def test_plan_benchmark_command_end_to_end(tmp_path, capsys):
    out = tmp_path / "pb"
    rc = main(["plan-benchmark", "--scenarios", "2", "--only", "1", "--ks", "20",
               "--random-poses", "40", "--validation", "20", "--candidates", "200",
               "--out", str(out), "--json"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    designs = {(d["design"], d["poses"]): d for d in doc["designs"]}
    assert set(designs) == {("random", 40), ("planned", 20)}
    for d in designs.values():          # scenario 1 hides a cyclic error (SNR >> 1)
        assert d["hidden"] == "cyclic_error" and d["expected"] == "cyclic_error"
        assert d["noise_rms"] > 0 and np.isfinite(d["ratio"])
        assert len(d["std"]) > 50
    assert designs[("random", 40)]["found"].startswith("cyclic_error")
    assert "| planned | 20 |" in (out / "summary.md").read_text()
    assert main(["plan-benchmark", "--scenarios", "2", "--only", "5", "--out",
                 str(tmp_path / "x")]) == 2


def test_measure_refuses_directions_it_cannot_follow():
    from sim.robot.instrument import Instrument
    from sim.robot.measurement import Procedure, measure
    from sim.robot.real import RealRobot

    robot = RealRobot(PUMA)
    q = np.zeros((3, 6))
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="directions"):
        measure(robot, q, Instrument(), rng, Procedure(approach="gravity"),
                directions=np.ones((3, 6)))
    with pytest.raises(InputError, match="directions"):
        measure(robot, q, Instrument(), rng, Procedure(approach="random"),
                directions=np.zeros((3, 6)))
