"""Issue 13, the readers and the Python API: every reproduction of the hostile-user report is a
named error (the project's hierarchy, naming the field, joint, file line or argument), the
correct number, or the file kept."""

from __future__ import annotations

import csv
import dataclasses
import io
import warnings

import numpy as np
import pytest

import zrp
from zrp.errors import InputError, ModelError, ModelFileError, ZRPError
from zrp.gap import Injection, load_measurements, synthesize
from zrp.gap.data.measurements import DataWarning
from zrp.gap.data.subsample import subsample_poses
from zrp.kinematics import uniform_joint_values
from zrp.model.files import dumps_model, loads_model

PUMA = zrp.load_model("puma")
PUMA_TEXT = dumps_model(PUMA)


@pytest.fixture(scope="module")
def meas():
    rng = np.random.default_rng(0)
    return synthesize(PUMA, uniform_joint_values(PUMA, 40, rng), Injection(), rng=rng,
                      tool_offsets=((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0)))


@pytest.fixture(scope="module")
def csv_rows(meas, tmp_path_factory):
    path = meas.to_csv(tmp_path_factory.mktemp("csv") / "d.csv")
    return list(csv.reader(io.StringIO(path.read_text())))


def _write_rows(tmp_path, rows, name="x.csv"):
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    p = tmp_path / name
    p.write_text(buf.getvalue(), encoding="utf-8")
    return p


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


# ---- joint values --------------------------------------------------------------------------
@pytest.mark.parametrize("q, match", [
    (np.zeros(6) + 1j, "expected real numbers.*complex128"),
    (np.zeros(6, dtype="datetime64[s]"), "expected real numbers.*datetime64"),
    (np.ma.masked_array(np.zeros(6), mask=[1, 0, 0, 0, 0, 0]), "masked array"),
    (np.full(6, 1e19), r"joint 1 \(q1\) is 1e\+19; expected finite values within \+-1e\+06 rad"),
    (np.full(6, 1e20), r"joint 1 \(q1\) is 1e\+20"),
    ([0, 0, 0, 0, 0, float("nan")], r"joint 6 \(q6\) is nan"),
])
@pytest.mark.parametrize("fn", [zrp.end_effector_pose, zrp.jacobian, zrp.forward_kinematics])
def test_joint_values_real_and_in_range(fn, q, match):
    with pytest.raises(InputError, match=match):
        fn(PUMA, q)


def test_large_but_accepted_angles_agree_with_numpy():
    """Up to the 1e6 rad limit the fast kernels give what NumPy's exactly reduced sin/cos give."""
    q = np.array([9.9e5, -7.7e5, 3.3e5, 1e5, -5e5, 8.8e5])
    p_fast, _ = zrp.end_effector_pose(PUMA, q)
    np.testing.assert_allclose(p_fast, zrp.forward_kinematics(PUMA, q).position, atol=1e-9)


def test_tolerances_bounded():
    with pytest.raises(InputError, match=r"tolerance of b1.x: expected a finite value from 0"):
        zrp.Tolerances.build(PUMA, length=1e308)
    with pytest.raises(InputError, match=r"tolerance of u1\.t1"):
        zrp.Tolerances.build(PUMA, angle_rad=4.0)


# ---- measurement CSV -----------------------------------------------------------------------
def test_latin1_byte_names_its_line(tmp_path, csv_rows):
    p = _write_rows(tmp_path, csv_rows)
    p.write_bytes(p.read_bytes() + "# café\n".encode("latin-1"))
    n = len(p.read_bytes().splitlines())
    with pytest.raises(InputError, match=rf"line {n}: byte 0xe9 is not UTF-8"):
        load_measurements(p, PUMA)


def test_utf16_with_bom_is_read(tmp_path, csv_rows, meas):
    p = _write_rows(tmp_path, csv_rows)
    p.write_bytes(p.read_text().encode("utf-16"))
    np.testing.assert_array_equal(load_measurements(p, PUMA).xyz, meas.xyz)


@pytest.mark.parametrize("text, match", [
    ("# a\n# b\n", "no header line"),
    (",,,\n,,\n", "no header line"),
    ("", "empty"),
])
def test_headerless_files(tmp_path, text, match):
    p = tmp_path / "h.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=match):
        load_measurements(p, PUMA)


def test_over_long_field_names_its_line(tmp_path, csv_rows):
    rows = [csv_rows[0], ["x" * 200000, *csv_rows[1][1:]]]
    with pytest.raises(InputError, match=r"line 2: field larger than field limit"):
        load_measurements(_write_rows(tmp_path, rows), PUMA)


@pytest.mark.parametrize("sep", ["\f", "\u2028", "\x1c", "\v"])
def test_line_separators_inside_quoted_fields(tmp_path, csv_rows, sep):
    """Only CR/LF end a CSV record: a form feed or U+2028 inside a pose id stays in it."""
    rows = [list(r) for r in csv_rows]
    rows[1][0] = f"a{sep}b"
    rows[2][0] = f"a{sep}b"  # same pose: the next row of it
    loaded = load_measurements(_write_rows(tmp_path, rows), PUMA)
    assert loaded.pose[0] == f"a{sep}b" and loaded.n_rows == len(rows) - 1


@pytest.mark.parametrize("value, row, line", [("1e300", "all", 2), ("1e308", 5, 6)])
def test_huge_positions_name_the_line(tmp_path, csv_rows, value, row, line):
    rows = [list(r) for r in csv_rows]
    ix = rows[0].index("x")
    for r in (rows[1:] if row == "all" else [rows[row]]):
        r[ix] = value
    shown = f"{float(value):g}".replace("+", r"\+")
    with pytest.raises(InputError, match=rf"line {line}: column x is {shown}.*up to 1e\+09"):
        load_measurements(_write_rows(tmp_path, rows), PUMA)


def test_measurements_from_arrays_bounded(meas):
    xyz = np.array(meas.xyz)
    xyz[3, 2] = 1e300
    with pytest.raises(InputError, match=r"line 5: column z"):
        zrp.gap.Measurements.from_arrays(meas.pose, meas.q, xyz, point=meas.point)


# ---- diagnose arguments --------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, match", [
    ({"model": None}, "model: expected a zrp.Manipulator"),
    ({"measurements": "d.csv"}, "measurements: expected zrp.gap.Measurements"),
    ({"seed": 1.5}, "seed: expected a whole number, got 1.5"),
    ({"seed": -1}, "seed: expected a whole number >= 0"),
    ({"folds": 2.5}, "folds: expected a whole number, got 2.5"),
    ({"folds": "5"}, "folds: expected a whole number"),
    ({"withheld_fraction": 0.99}, r"withheld_fraction: expected a finite number in \(0, 0.5\]"),
    ({"alpha": float("nan")}, "alpha"),
    ({"effects": "backlash"}, "effects: expected a sequence"),
    ({"rng": 0}, "rng: expected a numpy.random.Generator"),
    ({"max_points": 0}, "max_points: expected a whole number >= 1"),
    ({"harmonics": (1.5,)}, "harmonics"),
])
def test_diagnose_arguments(meas, kwargs, match):
    args = {"model": PUMA, "measurements": meas, **kwargs}
    with pytest.raises(InputError, match=match):
        zrp.diagnose(args.pop("model"), args.pop("measurements"), **args)


def test_noise_is_blamed_on_the_noise():
    rng = np.random.default_rng(0)
    noisy = synthesize(PUMA, uniform_joint_values(PUMA, 100, rng), Injection(), rng=rng,
                       noise_sigma=100.0, tool_offsets=((50.0, 0, 30), (-40.0, 60, 30),
                                                        (0.0, -50, 30)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError, match="the measurements themselves scatter") as exc:
            zrp.diagnose(PUMA, noisy)
    assert "joint order" not in str(exc.value)


def test_subsample_rule_is_seeded_whole_poses_and_announced(meas):
    with pytest.warns(DataWarning, match=r"exceed max_points=30.*default_rng\(7\)"):
        sub, kept = subsample_poses(meas, 30, seed=7)
    assert sub.n_rows <= 30 and sub.n_rows % 2 == 0  # two points per pose, never split
    assert np.all(np.diff(kept) > 0)                   # measurement order kept
    with pytest.warns(DataWarning):
        _again, kept2 = subsample_poses(meas, 30, seed=7)
    np.testing.assert_array_equal(kept, kept2)
    np.testing.assert_array_equal(sub.xyz, meas.xyz[np.isin(meas.pose_index, kept)])
    assert subsample_poses(meas, meas.n_rows, seed=7)[1] is None


def test_diagnosis_records_the_subsample(meas):
    big = synthesize(PUMA, uniform_joint_values(PUMA, 120, np.random.default_rng(3)),
                     Injection(joint_offset={2: 1e-3}), rng=np.random.default_rng(4),
                     tool_offsets=((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        diag = zrp.diagnose(PUMA, big, max_points=160, max_steps=1, seed=0)
    assert any("exceed max_points=160" in w for w in diag.warnings)
    assert diag.to_dict()["warnings"] == list(diag.warnings)


def test_only_project_errors_for_wrong_types(tmp_path):
    for call in (lambda: load_measurements(None, PUMA),
                 lambda: load_measurements(tmp_path / "none.csv", None),
                 lambda: loads_model(b"name = 1"),
                 lambda: zrp.jacobian(PUMA, "abc")):
        with pytest.raises(ZRPError):
            call()


@pytest.mark.parametrize("call, match", [
    (lambda: zrp.track_trajectory(None, zrp.puma_circle().trajectory, np.zeros(6), steps=10),
     "model: expected a zrp.Manipulator"),
    (lambda: zrp.uniform_joint_values(PUMA, -1, np.random.default_rng(0)),
     "count: expected a whole number >= 0"),
    (lambda: zrp.uniform_joint_values(PUMA, 3, 0), "rng: expected a numpy.random.Generator"),
    (lambda: synthesize(PUMA, None, Injection(), rng=np.random.default_rng(0)), "q: expected"),
    (lambda: zrp.from_dh(None), "rows: expected a sequence of DH rows"),
    (lambda: zrp.from_dh([["a", 0, 0, 0]]), "DH row 1"),
    (lambda: zrp.gap.Measurements.from_arrays(["a"], [["x"] * 6], [[0, 0, 0]]),
     "q and xyz: expected numbers"),
])
def test_public_api_wrong_types(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_too_many_rows_refused_with_guidance(tmp_path, csv_rows):
    path = _write_rows(tmp_path, csv_rows)
    with pytest.raises(InputError, match=r"line 12: more than max_rows=10 data rows.*split the"):
        load_measurements(path, PUMA, max_rows=10)
    assert load_measurements(path, PUMA, max_rows=None).n_rows == len(csv_rows) - 1
