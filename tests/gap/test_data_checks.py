"""The measurement reader and the diagnosis's arguments on hostile input (issue 13): every
reproduction of the hostile-user report is a named error (naming the file line, column or
argument), the correct number, or a stated subsample. The model-file reader's share is in
tests/model/test_file_checks.py, the rest of the Python API's in
tests/contracts/test_api_input_checks.py."""

from __future__ import annotations

import csv
import io
import warnings

import numpy as np
import pytest

import zrp
from zrp.errors import InputError
from zrp.gap import Injection, load_measurements, synthesize
from zrp.gap.data.measurements import DataWarning
from zrp.gap.data.subsample import subsample_poses
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


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


def test_degrees_passed_as_radians_are_refused_where_the_model_meets_them(meas):
    """Issue 35, finding 11: from_arrays took degrees silently. It cannot tell a revolute column
    from a prismatic one; the model can: a revolute value beyond one turn (or the joint's
    limit) is refused as degrees, naming the row and joint; the same poses in rad pass."""
    from zrp.errors import UnitError
    from zrp.gap.model.context import Context

    deg = zrp.gap.Measurements.from_arrays(meas.pose, np.degrees(meas.q), meas.xyz,
                                           point=meas.point)
    i, k = (int(v) for v in np.argwhere(np.abs(deg.q) > 2 * np.pi)[0])
    with pytest.raises(UnitError, match=rf"row {i + 1}: joint {k + 1} .*looks like degrees"):
        zrp.diagnose(PUMA, deg)
    assert Context(PUMA, meas).n == PUMA.n


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


def test_too_many_rows_refused_with_guidance(tmp_path, csv_rows):
    path = _write_rows(tmp_path, csv_rows)
    with pytest.raises(InputError, match=r"line 12: more than max_rows=10 data rows.*split the"):
        load_measurements(path, PUMA, max_rows=10)
    assert load_measurements(path, PUMA, max_rows=None).n_rows == len(csv_rows) - 1
