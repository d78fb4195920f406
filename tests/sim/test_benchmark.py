"""The blind benchmark: the truth never reaches the diagnosis, runs are reproducible from the
seed, and the scoring judges what it says it judges."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import sim.studies.benchmark as gb
import zrp
from sim.robot.effects import HiddenEffects
from sim.studies.benchmark import (
    BenchmarkConfig,
    confusion_matrix,
    draw_scenarios,
    effect_signatures,
    registered_rms,
    run_benchmark,
    score,
    summary_rows,
    write_outputs,
)
from zrp.cli.app import main
from zrp.errors import InputError

SMALL = {"poses": 40, "none_fraction": 0.0, "pair_fraction": 0.0}

# ---- file-access audit: which files does the blind diagnosis open? -----------------------
_OPENED: list[str] | None = None


def _audit(event: str, args: tuple) -> None:
    if _OPENED is not None and event == "open" and args and isinstance(args[0], (str, Path)):
        _OPENED.append(str(args[0]))


sys.addaudithook(_audit)


def test_truth_never_reaches_the_diagnosis(puma, tmp_path, monkeypatch):
    """The diagnosis gets the CSV path, the nominal model and the nominal MJCF - nothing else -
    opens no truth file, and gives the same answer when the truth files are gone."""
    global _OPENED
    calls = []
    real = gb.blind.diagnose_blind_result      # what the runner calls (diagnose_blind's core)

    def spy(csv_path, model, **kw):
        global _OPENED
        calls.append((csv_path, model, kw))
        _OPENED = []
        try:
            return real(csv_path, model, **kw)
        finally:
            calls[-1] = (*calls[-1], list(_OPENED))
            _OPENED = None

    monkeypatch.setattr(gb.runner, "diagnose_blind_result", spy)
    cfg = BenchmarkConfig(scenarios=2, seed=5, **SMALL)
    res = run_benchmark(puma, cfg, tmp_path, progress=False)
    assert len(calls) == 2 and len(res.scores) == 2
    truth_dir = (tmp_path / "truth").resolve()
    for csv_path, model, kw, opened in calls:
        # the arguments: a CSV in the measurement folder, the nominal model, MJCF path, seed
        assert Path(csv_path).parent.resolve() == (tmp_path / "measurements").resolve()
        assert Path(csv_path).suffix == ".csv"
        assert model is puma
        assert set(kw) == {"mjcf_path", "seed"}
        assert Path(kw["mjcf_path"]).name == "nominal.xml"
        assert isinstance(kw["seed"], int)
        # files opened while diagnosing: the CSV and the nominal MJCF, never a truth file
        opened_paths = {Path(p).resolve() for p in opened if Path(p).suffix in
                        (".csv", ".json", ".xml")}
        assert Path(csv_path).resolve() in opened_paths
        assert not any(truth_dir in p.parents for p in opened_paths)
        assert not any(p.name.endswith(".truth.json") for p in opened_paths)
    # the nominal MJCF is the nominal model, not the real robot
    xml = (tmp_path / "nominal.xml").read_text()
    assert "motor" not in xml and "payload" not in xml
    # same answer without the truth files
    first_csv = calls[0][0]
    before = gb.diagnose_blind(first_csv, puma, mjcf_path=calls[0][2]["mjcf_path"], seed=0)
    for f in (tmp_path / "truth").iterdir():
        f.unlink()
    after = gb.diagnose_blind(first_csv, puma, mjcf_path=calls[0][2]["mjcf_path"], seed=0)
    assert json.dumps(before, sort_keys=True, default=str) == \
        json.dumps(after, sort_keys=True, default=str)


def _strip_times(d):
    return [{k: v for k, v in s.items() if k not in ("sim_s", "diag_s")} for s in d]


def test_benchmark_runs_are_reproducible_from_the_seed(puma, tmp_path):
    cfg = BenchmarkConfig(scenarios=2, seed=11, **SMALL)
    a = run_benchmark(puma, cfg, tmp_path / "a", progress=False)
    b = run_benchmark(puma, cfg, tmp_path / "b", progress=False)
    assert _strip_times([s.to_dict() for s in a.scores]) == \
        _strip_times([s.to_dict() for s in b.scores])
    for name in ("scenario_000.csv", "scenario_001.csv"):
        assert (tmp_path / "a/measurements" / name).read_bytes() == \
            (tmp_path / "b/measurements" / name).read_bytes()
    # an interrupted run resumes: the score written as it arrived is kept, the missing one
    # is run again and the result is the same (worker processes: tests/cli/test_cluster.py)
    (tmp_path / "a/scores/scenario_001.score.json").unlink()
    c = run_benchmark(puma, cfg, tmp_path / "a", progress=False, resume=True)
    assert c.resumed == 1 and not c.failures
    assert _strip_times([s.to_dict() for s in c.scores]) == \
        _strip_times([s.to_dict() for s in a.scores])
    # a different seed gives different scenarios and measurements
    other = draw_scenarios(puma, BenchmarkConfig(scenarios=2, seed=12, **SMALL))
    mine = draw_scenarios(puma, cfg)
    assert [s.effects for s in other] != [s.effects for s in mine]


def test_scenarios_do_not_depend_on_how_many_are_drawn(puma):
    three = draw_scenarios(puma, BenchmarkConfig(scenarios=3, seed=4))
    six = draw_scenarios(puma, BenchmarkConfig(scenarios=6, seed=4))
    for a, b in zip(three, six[:3], strict=True):
        assert a.effects == b.effects and a.seed == b.seed and a.noise_sigma == b.noise_sigma
    kinds = [s.kind for s in draw_scenarios(puma, BenchmarkConfig(
        scenarios=200, seed=1, none_fraction=0.2, pair_fraction=0.3))]
    assert 0.1 < kinds.count("none") / 200 < 0.3 and 0.2 < kinds.count("pair") / 200 < 0.4
    for s in draw_scenarios(puma, BenchmarkConfig(scenarios=40, seed=2)):
        assert len(s.effects.active) == {"none": 0, "single": 1, "pair": 2}[s.kind]
        assert 0.01 <= s.noise_sigma <= 0.03


def _fake_truth(puma, effects, q, sigma=0.02):
    """A truth dict as the measuring procedure writes it, with exact joint values."""
    from sim.robot.effects import default_tool_points, motor_map

    qm = motor_map(effects, q)
    return {"effects": effects.to_dict(), "instrument": {"noise_sigma": sigma},
            "robot": {"tool_points": default_tool_points(puma).tolist(), "t_ref_degC": 20.0},
            "poses": {"q_command": q.tolist(), "q_link": qm.tolist(), "q_motor": qm.tolist(),
                      "temperature_true": np.full(len(q), 25.0).tolist()},
            "scenario": {"index": 0, "kind": "single", "labels": list(effects.active)}}


def _diag(steps, nominal=0.3, final=0.035):
    return {"steps": [{"effect": e, "joints": j} for e, j in steps],
            "nominal": {"rms": nominal}, "final": {"rms": final}, "unexplained": False}


def test_excitation_sees_what_registration_absorbs(puma):
    q = np.random.default_rng(0).uniform(-2.5, 2.5, (60, 6))
    # a joint-1 offset only turns the arm about the base z axis: the instrument frame absorbs it
    # (up to the second-order terms of the linearised registration, ~1e-6 x reach)
    sig = effect_signatures(puma, _fake_truth(puma, HiddenEffects(joint_offset={1: 1e-3}), q))
    assert sig["joint_offset"] < 1e-3
    # a joint-6 offset turns the tool about its own axis: the tool offsets absorb it
    sig = effect_signatures(puma, _fake_truth(puma, HiddenEffects(joint_offset={6: 1e-3}), q))
    assert sig["joint_offset"] < 1e-3
    # a joint-3 offset does not hide
    sig = effect_signatures(puma, _fake_truth(puma, HiddenEffects(joint_offset={3: 1e-3}), q))
    assert sig["joint_offset"] > 0.1
    # a rigid motion of all points is fully absorbed; a scaling is not
    tool = np.zeros((1, 3))
    fk = zrp.forward_kinematics(puma, q)
    pts = fk.position[:, None, :]
    rot = np.cross(np.array([1e-4, -2e-4, 3e-4]), pts) + np.array([0.5, -0.2, 0.1])
    assert registered_rms(puma, q, tool, rot) < 1e-6
    assert registered_rms(puma, q, tool, 1e-4 * pts) > 0.02


def test_scoring_rules(puma):
    q = np.random.default_rng(1).uniform(-2.5, 2.5, (60, 6))
    cfg = BenchmarkConfig()
    truth = _fake_truth(puma, HiddenEffects(joint_offset={3: 1e-3}), q)
    ok = score(puma, truth, _diag([("joint_offset", [3])]), cfg)
    assert ok.top_correct and ok.joints_correct and ok.success
    assert ok.ratio == pytest.approx(0.035 / (np.sqrt(3) * 0.02))
    assert ok.shrink == pytest.approx(0.035 / 0.3)
    wrong_joint = score(puma, truth, _diag([("joint_offset", [2])]), cfg)
    assert wrong_joint.top_correct and not wrong_joint.joints_correct
    look_alike = score(puma, truth, _diag([("axis_misalignment", [3])]), cfg)
    assert not look_alike.top_correct and "look-alike" in look_alike.note
    missed = score(puma, truth, _diag([], final=0.3), cfg)
    assert not missed.top_correct and "missed" in missed.note
    high = score(puma, truth, _diag([("joint_offset", [3])], final=0.2), cfg)
    assert high.top_correct and not high.success
    # an invisible effect: "none" is right, and so is naming the hidden effect
    hidden = _fake_truth(puma, HiddenEffects(joint_offset={1: 1e-3}), q)
    assert score(puma, hidden, _diag([]), cfg).top_correct
    assert score(puma, hidden, _diag([("joint_offset", [1])]), cfg).top_correct
    assert not score(puma, hidden, _diag([("backlash", [2])]), cfg).top_correct
    # a refusal (e.g. poses that cannot register the data) is reported, never counted right
    refused = score(puma, truth, {"steps": [], "nominal": {"rms": float("nan")},
                                  "final": {"rms": float("nan")}, "unexplained": None,
                                  "error": "x.csv: the registration is not identifiable"},
                    cfg)
    assert refused.found == ("refused",) and not refused.top_correct and not refused.success
    assert "refused the data: the registration is not identifiable" in refused.note
    # pairs: first named must be one of them; both found is reported separately
    pair = _fake_truth(puma, HiddenEffects(joint_offset={3: 1e-3},
                                           encoder_scale={2: 5e-4}), q)
    pair["scenario"]["kind"] = "pair"
    s = score(puma, pair, _diag([("encoder_scale", [2]), ("joint_offset", [3])]), cfg)
    assert s.top_correct and s.all_found
    s = score(puma, pair, _diag([("encoder_scale", [2])], final=0.1), cfg)
    assert s.top_correct and not s.all_found


def test_tables_and_outputs(puma, tmp_path):
    cfg = BenchmarkConfig(scenarios=3, seed=3, poses=40, none_fraction=0.34,
                          pair_fraction=0.33)
    res = run_benchmark(puma, cfg, tmp_path / "work", progress=False)
    conf = confusion_matrix(res)
    assert sum(sum(r.values()) for r in conf.values()) == \
        sum(s.kind != "pair" for s in res.scores)
    groups = [r["group"] for r in summary_rows(res)]
    assert "single, visible" in groups and "single, all" in groups
    files = write_outputs(res, tmp_path / "out")
    assert {f.name for f in files} == set(gb.OUTPUT_FILES)
    text = (tmp_path / "out/summary.md").read_text()
    assert "Confusion matrix" in text and "Summary" in text
    data = json.loads((tmp_path / "out/results.json").read_text())
    assert len(data["scenarios"]) == 3
    with pytest.raises(zrp.OutputExistsError, match="--force"):
        write_outputs(res, tmp_path / "out")


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"scenarios": 0}, "scenarios"),
    ({"poses": 5}, "poses"),
    ({"seed": -1}, "seed"),
    ({"none_fraction": 0.7, "pair_fraction": 0.5}, r"> 1"),
    ({"effects": ("wobble",)}, "unknown"),
    ({"effects": ("backlash",), "pair_fraction": 0.2}, "two effects"),
    ({"noise": (0.03, 0.01)}, "noise"),
    ({"poses_from": "spiral"}, "poses_from"),
    ({"approach": "sideways"}, "approach"),
])
def test_config_rejects_bad_options(kwargs, match):
    with pytest.raises(InputError, match=match):
        BenchmarkConfig(**kwargs)


def test_cli_measure_and_benchmark(tmp_path, capsys):
    out = tmp_path / "m.csv"
    assert main(["measure", "--out", str(out), "--poses", "12", "--effect",
                 "joint_offset:3=0.5mrad", "--seed", "1", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["effects"] == ["joint_offset"] and Path(info["truth"]).exists()
    assert Path(info["truth"]).name == "m.truth.json"
    assert main(["measure", "--out", str(out), "--poses", "12"]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["measure", "--out", str(tmp_path / "x.csv"), "--effect", "backlash=1"]) == 2
    assert "needs a joint" in capsys.readouterr().err
    assert main(["measure", "--out", str(tmp_path / "y.csv"), "--poses", "3"]) == 2
    assert "--poses" in capsys.readouterr().err
    bench = tmp_path / "bench"
    args = ["gap-benchmark", "--scenarios", "1", "--poses", "40", "--none", "0", "--pairs", "0",
            "--out", str(bench), "--no-plots", "--no-progress"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "Confusion matrix" in text and (bench / "summary.md").exists()
    assert (bench / "work/truth/scenario_000.truth.json").exists()
    assert main(args) == 2
    assert "--force" in capsys.readouterr().err


def test_blind_diagnosis_names_a_physical_backlash(puma, tmp_path):
    """End to end through files: a 1 mrad play on joint 1 (no gravity torque), 80 poses,
    measured and written; the blind diagnosis of the CSV alone names backlash on joint 1
    and ends at the noise floor."""
    from sim.robot.instrument import Instrument
    from sim.robot.measurement import measure, write_measurements
    from sim.robot.real import RealRobot
    from zrp.kinematics import reachable_poses

    rng = np.random.default_rng(21)
    run = measure(RealRobot(puma, HiddenEffects(backlash={1: 1e-3})),
                  reachable_poses(puma, 80, rng), Instrument(noise_sigma=0.015), rng)
    csv_path = write_measurements(run, tmp_path / "m.csv")
    diag = gb.diagnose_blind(csv_path, puma, mjcf_path=None, seed=0)
    assert diag["steps"][0]["effect"] == "backlash"
    assert diag["steps"][0]["joints"] == [1]
    assert diag["final"]["rms"] < 1.5 * np.sqrt(3) * 0.015
