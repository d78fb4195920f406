"""The model-file reader and the model's constructors on hostile input (issue 13): every
value of a TOML model file is checked and named with its line, names round-trip whatever
they hold, and the line of an error is found in linear time."""

from __future__ import annotations

import dataclasses

import pytest

import zrp
from zrp.errors import ModelError, ModelFileError
from zrp.model.files import dumps_model, loads_model

PUMA = zrp.load_model("puma")
PUMA_TEXT = dumps_model(PUMA)


# ---- model files -----------------------------------------------------------------------------
@pytest.mark.parametrize("edit, match", [
    (lambda t: "joint = [1, 2]\n" + t.split("[[joint]]", 1)[0].replace('name = "', 'x = "', 0)
     + "[end_effector]" + t.split("[end_effector]")[1], r"joint: no \[\[joint\]\] tables"),
    (lambda t: t.replace("axis = [0, 0, 1]", 'axis = ["0", "0", "1"]', 1),
     r"line 6: joint 1 axis: expected 3 numbers, got \['0', '0', '1'\]"),
    (lambda t: t.replace("axis = [0, 0, 1]", "axis = [false, false, true]", 1),
     r"line 6: joint 1 axis: expected 3 numbers"),
    (lambda t: t.replace('length_unit = "mm"', 'length_unit = "furlong"'),
     r"line 2: length_unit: unknown length unit 'furlong'"),
    (lambda t: t.replace("body = [0, 0, -127]", "body = [0, 0, 1e308]"),
     r"end_effector body: component 1e\+308 is out of range; expected magnitudes up to 1e\+09"),
    (lambda t: t.replace('name = "PUMA', 'name = 5\nx = "PUMA', 1), "unknown key 'x'"),
    (lambda t: t.replace('type = "revolute"', "type = [1]", 1), "joint 1 type"),
])
def test_model_file_values_are_checked(edit, match):
    with pytest.raises(ModelFileError, match=match):
        loads_model(edit(PUMA_TEXT), "m.toml")


@pytest.mark.parametrize("bad", [None, 3, b"puma", ""])
def test_load_model_refuses_non_paths(bad):
    with pytest.raises(ModelFileError, match="path: expected a model file name"):
        zrp.load_model(bad)


def test_saved_names_with_control_characters_round_trip(tmp_path):
    weird = dataclasses.replace(PUMA, name='a\nb\x01c"\\d\u2028e\x7f')
    path = zrp.save_model(weird, tmp_path / "m.toml")
    assert zrp.load_model(path).name == weird.name


def test_short_joint_names_are_refused():
    with pytest.raises(ModelError, match="joint_names: expected 6 strings"):
        zrp.Manipulator.from_arrays(PUMA.axes, PUMA.bodies, axial=PUMA.end_effector.axial,
                                    transverse=PUMA.end_effector.transverse, joint_names=("a",))


def test_model_file_line_lookup_is_linear_in_the_joints():
    """4,000 joints parsed (66 s before the fix); the line of an error in the last joint is
    still found (not a timed test: the benchmark measures the scaling)."""
    head, rest = PUMA_TEXT.split("[[joint]]", 1)
    joint = "[[joint]]" + rest.split("[[joint]]")[0].split("[end_effector]")[0]
    ee = "[end_effector]" + PUMA_TEXT.split("[end_effector]")[1]
    text = head + joint * 3999 + joint.replace("axis = [0, 0, 1]", "axis = [0, 0, 0]") + ee
    with pytest.raises(ModelFileError, match=r"joint 4000 axis: is a zero vector") as exc:
        loads_model(text, "big.toml")
    line = int(str(exc.value).split("line ")[1].split(":")[0])
    assert text.splitlines()[line - 1].startswith("axis = [0, 0, 0]")


def test_a_model_name_over_the_file_system_limit_is_a_named_error(tmp_path):
    """Path.exists raises ENAMETOOLONG for a 400-character name (found by the 5,000-case
    compensation fuzz: a model_file field of 400 digits)."""
    from zrp.model.files import ModelFileError, load_model

    with pytest.raises(ModelFileError, match="not a usable file name"):
        load_model(tmp_path / ("9" * 400 + ".toml"))
