"""``zrp calibrate --diagnosis D/diagnosis.json`` (issue 33): a stored diagnosis is reused
without repeating the search and gives the same calibrated.toml and compensation.json, byte
for byte, as a fresh ``zrp calibrate`` on the same data; a diagnosis of other measurements,
of another model or written before diagnosis.json held its final model's record is refused
by name."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.calibration import calibrate
from zrp.cli.app import main
from zrp.gap import Injection, load_measurements, synthesize
from zrp.gap.finalrecord import StaleDiagnosisError
from zrp.gap.report import diagnosis_document
from zrp.jsonio import dumps
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
FILES = ("calibrated.toml", "compensation.json")


def _zrp(*args: str) -> int:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return main(list(args))


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Path:
    """Synthetic PUMA data (offsets, a play, a compliance), calibrated afresh, diagnosed
    alone, and calibrated again from each stored diagnosis."""
    rng = np.random.default_rng(11)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 140, rng),
                      Injection(joint_offset={2: 1e-3, 4: -8e-4}, backlash={3: 6e-4},
                                compliance={2: 2e-5}, masses={"ee": 5.0}),
                      rng=rng, noise_sigma=0.02)
    root = tmp_path_factory.mktemp("reuse")
    meas.to_csv(root / "d.csv", deg=True)
    common = ("--model", "puma", "--data", str(root / "d.csv"), "--deg")
    assert _zrp("calibrate", *common, "--no-progress", "--out", str(root / "fresh")) == 0
    assert _zrp("diagnose", *common, "--no-progress", "--no-plots",
                "--out", str(root / "diag")) == 0
    for src, out in (("diag", "reused"), ("fresh", "reused_fresh")):
        assert _zrp("calibrate", *common, "--diagnosis", str(root / src / "diagnosis.json"),
                    "--no-progress", "--out", str(root / out)) == 0
    return root


@pytest.mark.parametrize("out", ["reused", "reused_fresh"])
def test_a_stored_diagnosis_gives_the_same_files(runs, out):
    for name in FILES:
        assert (runs / out / name).read_bytes() == (runs / "fresh" / name).read_bytes(), name
    # the reuse writes the calibration only: no second diagnosis beside it
    assert sorted(p.name for p in (runs / out).iterdir()) == sorted(FILES)


def test_the_record_is_in_diagnosis_json(runs):
    doc = json.loads((runs / "diag" / "diagnosis.json").read_text(encoding="utf-8"))
    assert doc["schema_version"] == 2
    rec = doc["final_model_record"]
    assert rec["version"] == 2 and len(rec["measurements_sha256"]) == 64
    comp = json.loads((runs / "fresh" / FILES[1]).read_text(encoding="utf-8"))
    # the written joint map is the record's, term by term (joints from 1)
    written = {t["name"]: t["value"] for t in comp["joint_map"]}
    stored = {p["name"]: p["value"] for p in rec["parameters"] if p["name"] in written}
    assert written == stored and written
    assert all(t["joint"] >= 1 for t in comp["joint_map"])


def test_progress_says_the_search_is_not_repeated(runs, capsys, tmp_path):
    assert _zrp("calibrate", "--model", "puma", "--data", str(runs / "d.csv"), "--deg",
                "--diagnosis", str(runs / "diag" / "diagnosis.json"),
                "--out", str(tmp_path / "o")) == 0
    assert "reusing the diagnosis" in capsys.readouterr().err


def test_other_measurements_are_refused_by_name(runs, tmp_path, capsys):
    lines = (runs / "d.csv").read_text(encoding="utf-8").splitlines()
    (tmp_path / "other.csv").write_text("\n".join(lines[:-3]) + "\n", encoding="utf-8")
    rc = _zrp("calibrate", "--model", "puma", "--data", str(tmp_path / "other.csv"), "--deg",
              "--diagnosis", str(runs / "diag" / "diagnosis.json"), "--no-progress",
              "--out", str(tmp_path / "o"))
    err = capsys.readouterr().err
    assert rc == 2 and "made from other measurements" in err and "SHA-256" in err
    assert not (tmp_path / "o").exists()


def test_another_model_is_refused_by_name(runs):
    ee = PUMA.end_effector
    other = zrp.Manipulator.from_arrays(PUMA.axes, PUMA.bodies, axial=ee.axial,
                                        transverse=ee.transverse, types=PUMA.joint_types,
                                        name="another arm", length_unit=PUMA.length_unit)
    meas = load_measurements(runs / "d.csv", other, deg=True)
    with pytest.raises(StaleDiagnosisError, match="other model"):
        calibrate(other, meas, diagnosis=runs / "diag" / "diagnosis.json")


def test_an_old_diagnosis_is_refused_with_what_to_do(runs, tmp_path):
    doc = json.loads((runs / "diag" / "diagnosis.json").read_text(encoding="utf-8"))
    del doc["final_model_record"]
    doc["schema_version"] = 1
    (tmp_path / "old.json").write_text(json.dumps(doc), encoding="utf-8")
    meas = load_measurements(runs / "d.csv", PUMA, deg=True)
    with pytest.raises(StaleDiagnosisError, match="re-run zrp diagnose"):
        calibrate(PUMA, meas, diagnosis=tmp_path / "old.json")


def test_options_of_the_diagnosis_are_refused_beside_it(runs, tmp_path, capsys):
    rc = _zrp("calibrate", "--model", "puma", "--data", str(runs / "d.csv"), "--deg",
              "--diagnosis", str(runs / "diag" / "diagnosis.json"), "--seed", "3",
              "--max-steps", "2", "--out", str(tmp_path / "o"))
    err = capsys.readouterr().err
    assert rc == 2 and "--seed, --max-steps" in err


def test_full_pose_reuse_gives_the_same_files(full_pose_diagnosis, tmp_path):
    """With measured orientations the calibration is the full-pose refit; the stored
    diagnosis (its JSON text) carries it, the probe rotation included."""
    diag = full_pose_diagnosis
    meas = diag.context.meas
    assert diag.full_pose is not None
    text = dumps(diagnosis_document(diag))
    (tmp_path / "diagnosis.json").write_text(text, encoding="utf-8")
    a = calibrate(PUMA, meas, diagnosis=diag)
    b = calibrate(PUMA, meas, diagnosis=tmp_path / "diagnosis.json")
    assert a.record is not None and a.record.probe is not None and a.record.source == "full_pose"
    a.write(tmp_path / "a" / FILES[0], tmp_path / "a" / FILES[1])
    b.write(tmp_path / "b" / FILES[0], tmp_path / "b" / FILES[1])
    for name in FILES:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    comp = json.loads((tmp_path / "b" / FILES[1]).read_text(encoding="utf-8"))
    assert comp["full_pose"]["probe_rotation"] is not None
