"""diagnosis.json's final-model record vouches for its own values (issue 41, findings 2 and 7).

0.5.0 checked only the SHA-256 of the measurements and the model: a joint offset of 1e6 rad
was written and read back, ``"joint": 0`` moved joint 2's correction to joint 6, ``-3`` or an
unknown ``kind`` dropped it, ``"joint": 99`` and counts of 1e999 raised IndexError and
OverflowError. Now the record carries ``content_sha256`` (written last, checked first: an
edit is refused, naming what to do) and every value is checked in its domain when the record
is made and when it is read (one checker, :mod:`zrp.gap.recordcheck`); an attacker who
recomputes the hash meets the domains, each refusal naming the field.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import calibrate
from zrp.cli.app import main
from zrp.errors import InputError
from zrp.gap import Injection, diagnose, synthesize
from zrp.gap.finalrecord import (
    FinalModelRecord,
    RecordDomainError,
    StaleDiagnosisError,
    TamperedRecordError,
)
from zrp.gap.recordcheck import content_sha256
from zrp.gap.report import diagnosis_document
from zrp.jsonio import dumps
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    """A real diagnosis of synthetic PUMA data (offsets on joints 2 and 4, a play on 3): the
    data file, the measurements and the diagnosis.json document."""
    rng = np.random.default_rng(11)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 140, rng),
                      Injection(joint_offset={2: 1e-3, 4: -8e-4}, backlash={3: 6e-4}),
                      rng=rng, noise_sigma=0.02)
    root = tmp_path_factory.mktemp("record")
    meas.to_csv(root / "d.csv")
    meas = zrp.gap.load_measurements(root / "d.csv", PUMA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        diag = diagnose(PUMA, meas)
    return root, meas, json.loads(dumps(diagnosis_document(diag)))


def _write(root, doc, edit, *, rehash: bool):
    """diagnosis.json with its record edited (and its content hash recomputed, as an attacker
    who knows the scheme would, when ``rehash``)."""
    doc = json.loads(json.dumps(doc))
    rec = doc["final_model_record"]
    edit(rec)
    if rehash:
        rec["content_sha256"] = content_sha256(rec)
    path = root / "edited.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _offset(rec, joint=2):
    return next(p for p in rec["parameters"] if p["name"] == f"q{joint}.offset")


def _calibrate(meas, path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(PUMA, meas, diagnosis=path)


def test_the_record_as_written_is_read(stored):
    root, meas, doc = stored
    rec = doc["final_model_record"]
    assert list(rec)[-1] == "content_sha256" and rec["content_sha256"] == content_sha256(rec)
    cal = _calibrate(meas, _write(root, doc, lambda r: None, rehash=False)).robot
    assert abs(cal.joint_offsets[1] - _offset(rec)["value"]) < 1e-15


def test_an_edited_record_is_refused_naming_what_to_do(stored):
    root, meas, doc = stored
    path = _write(root, doc, lambda r: _offset(r).update(value=0.36), rehash=False)
    with pytest.raises(TamperedRecordError, match=r"changed after zrp diagnose wrote it.*"
                                                  r"re-run zrp diagnose"):
        _calibrate(meas, path)


def test_a_record_of_0_5_0_without_its_hash_is_stale(stored):
    root, meas, doc = stored

    def old(r):
        r["version"] = 1
        del r["content_sha256"]

    with pytest.raises(StaleDiagnosisError, match=r"version 1.*no content_sha256.*re-run zrp"):
        _calibrate(meas, _write(root, doc, old, rehash=False))


def _set(key, value):
    return lambda r: r.update({key: value})


def _param(**kw):
    return lambda r: _offset(r).update(kw)


@pytest.mark.parametrize("edit, field", [
    (_param(value=1e6), r"q2\.offset: joint offset 1e\+06; expected at most 3\.14"),
    (_param(joint=0), r"parameters\[\d+\]\.joint: 0; expected a whole number in 1\.\.64"),
    (_param(joint=6), r"name 'q2\.offset' is not joint 6's"),
    (_param(joint=-3), r"parameters\[\d+\]\.joint: -3"),
    (_param(joint=99), r"parameters\[\d+\]\.joint: 99"),
    (_param(joint=2.0), r"parameters\[\d+\]\.joint: 2\.0"),
    (_param(kind="dz"), "kind 'dz'; expected dq or thermal"),
    (_param(effect="warp"), "effect 'warp'"),
    (_param(value="0.001"), r"parameters\[\d+\]\.value: '0\.001'; expected a number"),
    (_set("harmonics", [0]), "harmonics: 0; expected a whole number in 1..100"),
    (_set("harmonics", [1, 1]), "harmonics: .*distinct"),
    (_set("base_rotation", np.diag([1.0, 1.0, -1.0]).tolist()), "base_rotation: a reflection"),
    (_set("base_translation", [1e9, 0.0, 0.0]), "base_translation: 1e\\+09 mm"),
    (_set("axes", [[0.0, 0.0, 1.0]] * 7), r"bodies: shape \(7, 3\); expected \(8, 3\)"),
    (_set("t_ref_degC", -400.0), "t_ref_degC"),
    (_set("frame", "world"), "frame: 'world'"),
    (_set("source", 3), "source: '3'"),
    (_set("gravity_dir", [0.0, 0.0, -2.0]), "gravity_dir"),
    (lambda r: r["backlash"].update(lead=["yes"] * 6), "backlash.lead"),
    (lambda r: r["backlash"].update(payload_kg=-1.0), "backlash.payload_kg"),
    (lambda r: r["tool_points"].update(s1=[1e7, 0.0, 0.0]), r"tool_points\['s1'\]"),
])
def test_a_rehashed_record_meets_the_domains(stored, edit, field):
    root, meas, doc = stored
    with pytest.raises(RecordDomainError, match=field):
        _calibrate(meas, _write(root, doc, edit, rehash=True))


@pytest.mark.parametrize("text, field", [
    ('"joint": 1e999', r"parameters\[\d+\]\.joint: inf"),
    ('"harmonics": [1e999]', "harmonics: inf"),
    ('"harmonics": [1, 2, 99999999999999999999999]', "harmonics: 9999"),
])
def test_huge_counts_are_named_not_overflow(stored, text, field):
    """1e999 is infinity to JSON readers: int() of it raised OverflowError in 0.5.0."""
    root, meas, doc = stored
    rec = doc["final_model_record"]
    raw = json.dumps(doc)
    key = text.split(":")[0]
    if key == '"joint"':
        old = '"name": "q2.offset", "effect": "joint_offset", "kind": "dq", "joint": 2'
        assert old in raw
        raw = raw.replace(old, old[:-len('"joint": 2')] + text)
    else:
        raw = raw.replace(f'"harmonics": {json.dumps(rec["harmonics"])}', text)
    new = content_sha256(json.loads(raw)["final_model_record"])  # as a reader parses it
    raw = raw.replace(rec["content_sha256"], new)
    (root / "huge.json").write_text(raw, encoding="utf-8")
    with pytest.raises(RecordDomainError, match=field):
        _calibrate(meas, root / "huge.json")


def test_the_writer_runs_the_readers_checks(stored):
    """A record made with a value outside its domain is refused when it is made, not only
    when it is read (one checker)."""
    _, _, doc = stored
    rec = FinalModelRecord.from_dict(doc["final_model_record"])
    p = rec.parameters[0]
    import dataclasses

    with pytest.raises(RecordDomainError, match=r"joint 0; expected 1\.\.6"):
        dataclasses.replace(rec, parameters=(dataclasses.replace(p, joint=0),))
    with pytest.raises(RecordDomainError, match=r"q2\.offset: joint offset"):
        dataclasses.replace(rec, parameters=(dataclasses.replace(
            next(q for q in rec.parameters if q.name == "q2.offset"), value=4.0),)
                            ).check_domains(PUMA)


def test_the_command_line_names_the_field_without_a_traceback(stored, capsys):
    root, _, doc = stored
    path = _write(root, doc, _param(joint=99), rehash=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"),
                   "--diagnosis", str(path), "--no-progress", "--out", str(root / "o")])
    err = capsys.readouterr().err
    assert rc == 2 and "joint: 99" in err and "Traceback" not in err
    assert not (root / "o").exists()
    assert issubclass(RecordDomainError, InputError)
