"""Issue 35, finding 11: leftovers of earlier rounds. Each ends in a named error (exit code 2,
one line naming the option or file, no traceback) or in correct behaviour."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.cli import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.units import LENGTH_UNITS


def _refused(capsys, argv: list[str], match: str) -> str:
    """Run ``zrp argv`` in-process: exit code 2 and ``match`` in the one-line error."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusal of an option value
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert match in err, err
    return err


def test_plan_with_fewer_candidates_than_poses_names_candidates(tmp_path: Path, capsys):
    out = tmp_path / "plan.csv"
    _refused(capsys, ["plan", "--model", "puma", "--poses", "10", "--effects", "joint_offset",
                      "--out", str(out), "--candidates", "1"], "--candidates: 1 candidate")
    assert not out.exists()


@pytest.mark.parametrize("damage", ["truncated", "wrong type", "not an object"])
def test_fleet_resume_over_a_damaged_diagnosis_names_the_file(tmp_path: Path, capsys, damage):
    model = zrp.load_model("puma")
    (tmp_path / "fleet").mkdir()
    for i in range(2):
        rng = np.random.default_rng(i)
        synthesize(model, uniform_joint_values(model, 40, rng), Injection(joint_offset={2: 2e-3}),
                   rng=rng, noise_sigma=0.02).to_csv(tmp_path / f"fleet/r{i}.csv")
    argv = ["diagnose", "--model", "puma", "--data", str(tmp_path / "fleet/*.csv"),
            "--no-plots", "--no-progress", "--tolerance", "0.5", "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    capsys.readouterr()
    path = tmp_path / "out/robots/r0/diagnosis.json"
    text = path.read_text(encoding="utf-8")
    doc = json.loads(text)
    doc["nominal"]["rms"] = "x"
    path.write_text({"truncated": text[:200], "wrong type": json.dumps(doc),
                     "not an object": "[1]"}[damage], encoding="utf-8")
    _refused(capsys, [*argv, "--resume"], f"--resume: {path}: not a diagnosis")


@pytest.mark.parametrize("address", ["bogus", "tcp://host:notaport"])
def test_tolerance_with_a_malformed_scheduler_address_names_scheduler(capsys, address):
    pytest.importorskip("distributed")
    _refused(capsys, ["tolerance", "--model", "puma", "--scheduler", address],
             f"--scheduler: cannot reach a Dask scheduler at {address!r}")


def test_ik_target_er_without_target_is_refused(tmp_path: Path, capsys):
    out = tmp_path / "joints.csv"
    _refused(capsys, ["ik", "--target-er", "1", "0", "0", "0", "--out", str(out)],
             "--target-er: only with --target")
    assert not out.exists()


@pytest.mark.parametrize("argv", [["mjcf", "--model", "puma"], ["mjcf", "--from", "arm.xml"],
                                  ["import", "arm.xml"]])
def test_an_unknown_length_unit_is_refused_listing_the_known_ones(tmp_path: Path, capsys, argv):
    out = tmp_path / "out.xml"
    err = _refused(capsys, [*argv, "--unit", "furlong", "--out", str(out)],
                   "argument --unit: unknown length unit 'furlong'")
    assert all(repr(u) in err for u in LENGTH_UNITS)
    assert not out.exists()


def test_mjcf_unit_without_from_is_refused(tmp_path: Path, capsys):
    out = tmp_path / "puma.xml"
    _refused(capsys, ["mjcf", "--model", "puma", "--unit", "m", "--out", str(out)],
             "--unit: only with --from")
    assert not out.exists()
