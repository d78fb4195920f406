"""Issue 35, finding 10: every field of compensation.json and calibrated.toml has a domain,
checked when the pair is read (each edit below re-binds the pair, so the field check, not the
hash, meets it), and a pair edited without re-binding is refused by the name of the changed
file. One case per field class: rotations, translations and tool points, units, conditions,
harmonics, thermal, shapes, JSON nesting and constants, the schema version."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from tests.calibration.pairs import write_bound
from zrp.calibration import CalibratedRobot, Term, read_calibration, write_calibration
from zrp.calibration.conditions import Conditions
from zrp.calibration.filecheck import FieldDomainError, PairWarning, TamperedPairError
from zrp.errors import InputError

PUMA = zrp.load_model("puma")


@pytest.fixture
def pair(tmp_path):
    cal = CalibratedRobot(
        PUMA, PUMA, np.eye(3), np.array([1.0, 2.0, 3.0]), ("s1",), np.array([[0.0, 0, 50]]),
        np.zeros(6), (Term("q2.backlash", "backlash", 2, "rad", 1e-4),),
        backlash_switch=(None, 3.0, None, None, None, None),
        gravity_side_weights=np.full((6, 4), 0.5),
        conditions=Conditions((0.0, 2.0), ("s1",), (20.0, 25.0), "mm",
                              ((-2.0, 2.0), *(None for _ in range(5)))))
    m, c = write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    return m, c


def _set(path, value):
    def edit(doc):
        target = doc
        for k in path[:-1]:
            target = target[k]
        target[path[-1]] = value
    return edit


CASES = [
    ("reflection", _set(["base_rotation"], [[1, 0, 0], [0, 1, 0], [0, 0, -1]]),
     r"base_rotation: a reflection"),
    ("translation 1e300", _set(["base_translation"], [1e300, 0, 0]), r"base_translation: inf"),
    ("translation 1 km", _set(["base_translation"], [1e6, 0, 0]),
     r"base_translation: 1e\+06 mm .* at most 100 x the arm's reach"),
    ("tool 1000 km", _set(["tool_points", "s1"], [1e9, 0, 0]), r"tool_points\['s1'\]"),
    ("furlong", _set(["length_unit"], "furlong"), r"length_unit: 'furlong'; expected one of"),
    # found by the fuzzer (5,000-case run): a list as the unit was a TypeError
    ("unit as a list", _set(["length_unit"], []), r"length_unit: \[\]; expected one of"),
    ("file in metres", _set(["length_unit"], "m"),
     r"length_unit: 'mm', but the model file's is 'm'"),
    ("conditions furlong", _set(["conditions", "length_unit"], "furlong"),
     r"conditions.length_unit: 'furlong'"),
    ("negative payload", _set(["conditions", "payloads_kg"], [-5.0]),
     r"conditions.payloads_kg: -5.0 kg"),
    ("inverted limits", _set(["conditions", "joint_limits", 0], [2.0, -2.0]),
     r"conditions.joint_limits\[1\]"),
    ("unordered temperatures", _set(["conditions", "temp_range_degC"], [30.0, 20.0]),
     r"temp_range_degC: \[30.0, 20.0\] is not ordered"),
    ("below absolute zero", _set(["conditions", "temp_range_degC"], [-300.0, 20.0]),
     r"temp_range_degC\[0\]"),
    ("harmonics 1e9", _set(["harmonics"], [1, 10**9]), r"harmonics: .* 1\.\.100"),
    ("t_ref 1e6 degC", _set(["thermal", "t_ref_degC"], 1e6), r"thermal.t_ref_degC: 1000000.0"),
    ("backlash payload", _set(["backlash", "payload_kg"], -1.0), r"backlash.payload_kg"),
    ("gravity_dir", _set(["gravity_dir"], [0, 0, -2]), r"gravity_dir"),
    ("scalar side weights", _set(["gravity_side_weights"], 5.0),
     r"gravity_side_weights: shape \(\); expected \(6, 4\)"),
    ("side weights (6, 3)", _set(["gravity_side_weights"], [[1.0] * 3] * 6),
     r"gravity_side_weights: shape \(6, 3\)"),
]


@pytest.mark.parametrize(("name", "edit", "match"), CASES, ids=[c[0] for c in CASES])
def test_a_field_outside_its_domain_is_refused_by_name(pair, name, edit, match):
    m, c = pair
    doc = json.loads(c.read_text())
    edit(doc)
    if name == "file in metres":  # the model file switched to metres, the pair re-bound
        m.write_text(m.read_text().replace('length_unit = "mm"', 'length_unit = "m"'))
        doc["length_unit"] = "mm"
    write_bound(c, doc)
    with pytest.raises(FieldDomainError, match=match):
        read_calibration(c)


@pytest.mark.parametrize(("text", "match"), [
    ("[" * 100_000 + "]" * 100_000, r"nested 100000 deep; .* at most 32"),
    ('{"schema_version": NaN}', r"NaN is not a JSON number"),
    ('{"schema_version": Infinity}', r"Infinity is not a JSON number"),
    ('{"schema_version": true}', r"schema_version true, expected one of 1, 2, 3 \(an integer\)"),
])
def test_json_nesting_constants_and_version(pair, text, match):
    _, c = pair
    c.write_text(text)
    with pytest.raises(InputError, match=match):
        read_calibration(c)


def test_a_changed_file_of_the_pair_is_named(pair):
    m, c = pair
    assert read_calibration(c).n == 6
    text = c.read_text()
    c.write_text(text.replace('"payload_kg": 0.0', '"payload_kg": 0.5'))
    with pytest.raises(TamperedPairError, match=r"compensation.json: its content is not"):
        read_calibration(c)
    c.write_text(text)
    m.write_text(m.read_text().replace("431.8", "431.9", 1))
    with pytest.raises(TamperedPairError, match=r"calibrated.toml: its SHA-256"):
        read_calibration(c)


def test_an_older_pair_without_hashes_is_read_with_a_warning(pair):
    _, c = pair
    doc = json.loads(c.read_text())
    doc["schema_version"] = 2  # as 0.4.0 wrote it: none of the keys version 3 added
    for key in ("model_sha256", "learned_residual", "taken_out_non_physical"):
        del doc[key]
    del doc["backlash"]["switch_weights"]
    c.write_text(json.dumps(doc))
    with pytest.warns(PairWarning, match="cannot be detected"):
        assert read_calibration(c).n == 6
    doc["schema_version"] = 3  # a version-3 file without its hash: refused
    c.write_text(json.dumps(doc))
    with warnings.catch_warnings(), pytest.raises(TamperedPairError):
        read_calibration(c)


def test_user_strings_cannot_add_keys_to_calibrated_toml(tmp_path):
    """The conditions' instrument and data file name head calibrated.toml as comments: a
    line break in them must not end the comment (it would add TOML keys)."""
    hostile = 'x\nlength_unit = "m"\n[[joint]]'
    cal = CalibratedRobot(
        PUMA, PUMA, np.eye(3), np.zeros(3), ("s1",), np.array([[0.0, 0, 50]]), np.zeros(6),
        conditions=Conditions((0.0,), ("s1",), None, "mm", tuple(None for _ in range(6)),
                              instrument=hostile, data_file=hostile + ".csv"))
    m, c = write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "c.json")
    head = m.read_text().split("\nname = ")[0].splitlines()
    assert all(line.startswith("#") for line in head), head
    back = read_calibration(c)
    assert back.model.length_unit == "mm" and back.n == 6
    assert back.conditions.data_file == hostile + ".csv"  # kept whole in the JSON
