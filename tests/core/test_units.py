"""The one unit rule (zrp/units.py) in every reader and command: every mix-up of degrees and
radians a user can make gives a named UnitError; declared units convert like numpy's radians
and scipy's length constants."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import constants

import zrp
from zrp.calibration.targets import load_targets
from zrp.cli import main
from zrp.errors import UnitError
from zrp.gap import load_measurements
from zrp.gap.motion import load_trajectory
from zrp.manufacturing.study import load_joint_csv
from zrp.units import (
    RADIAN_LOOK_MIN,
    RADIAN_LOOK_ROWS,
    joint_values_to_rad,
    si_factor,
    split_unit,
)

PUMA = zrp.load_model("puma")
Q_RAD = np.array([[0.1, -0.4, 0.6, 1.2, -0.9, 2.0], [0.5, 0.2, -1.1, 0.3, 0.8, -2.5],
                  [-1.0, 0.7, 0.4, -0.6, 1.5, 0.9]])


def _meas_csv(tmp_path, q, header_q=None, xyz_unit=""):
    cols = header_q or [f"q{k}" for k in range(1, 7)]
    lines = [",".join(["pose", "point", *cols, f"x{xyz_unit}", f"y{xyz_unit}", f"z{xyz_unit}"])]
    for i, row in enumerate(q):
        lines.append(",".join([f"P{i}", "a", *map(repr, map(float, row)), "1.5", "-2", "3"]))
    p = tmp_path / "m.csv"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_split_unit():
    assert split_unit("q1[deg]") == ("q1", "deg")
    assert split_unit(" x [ m ] ") == ("x", "m")
    assert split_unit("pose") == ("pose", None)
    for bad in ("q1[deg", "q1]", "q1[]", "[deg]"):
        with pytest.raises(UnitError, match="NAME"):
            split_unit(bad)


def test_si_factor_against_scipy_constants():
    assert si_factor("velocity", "deg/s") == pytest.approx(constants.degree)
    assert si_factor("position", "in") == pytest.approx(constants.inch)
    assert si_factor("time", "us") == pytest.approx(constants.micro)
    assert si_factor("effort", "mNm") == pytest.approx(constants.milli)
    assert si_factor("mass", "g") == pytest.approx(constants.gram)
    assert si_factor("current", None) == 1.0
    with pytest.raises(UnitError, match=r"column i1 has unit \[kA\]; a current column takes "
                                        r"one of A, ma$"):
        si_factor("current", "kA", "column i1")


def test_measurements_degrees_in_a_radian_column(tmp_path):
    with pytest.raises(UnitError, match=r"line 2: column q2 is -22.9.*like degrees.*q2\[deg\]"):
        load_measurements(_meas_csv(tmp_path, np.degrees(Q_RAD)), PUMA)


def test_measurements_radians_in_a_degree_column(tmp_path):
    with pytest.raises(UnitError, match="look like radians in a degree column"):
        load_measurements(_meas_csv(tmp_path, Q_RAD), PUMA, deg=True)
    declared = [f"q{k}[deg]" for k in range(1, 7)]
    with pytest.raises(UnitError, match="look like radians in a degree column"):
        load_measurements(_meas_csv(tmp_path, Q_RAD, declared), PUMA)


def test_declared_units_convert_like_numpy_and_scipy(tmp_path):
    declared = [f"q{k}[deg]" for k in range(1, 7)]
    m = load_measurements(_meas_csv(tmp_path, np.degrees(Q_RAD), declared, "[m]"), PUMA)
    assert np.allclose(m.q, Q_RAD, rtol=0, atol=1e-12)  # no deg=True needed: declared
    assert np.allclose(m.xyz[0], np.array([1.5, -2, 3]) / constants.milli)  # m -> mm
    m2 = load_measurements(_meas_csv(tmp_path, np.degrees(Q_RAD)), PUMA, deg=True)
    assert np.allclose(m2.q, Q_RAD, atol=1e-12)


@pytest.mark.parametrize(("column", "match"), [
    ("q1[rad]", "declares rad but deg=True"),
    ("q1[mm]", "q1 is revolute; expected rad or deg"),
    ("q1[grad]", "unknown angle unit 'grad'"),
])
def test_declared_units_that_cannot_hold(tmp_path, column, match):
    cols = [column, *[f"q{k}" for k in range(2, 7)]]
    with pytest.raises(UnitError, match=match):
        load_measurements(_meas_csv(tmp_path, np.degrees(Q_RAD), cols), PUMA, deg=True)


def test_an_angle_unit_on_a_prismatic_joint(tmp_path):
    scara = zrp.load_model("scara") if "scara" in zrp.builtin_models() else None
    if scara is None:
        pytest.skip("no built-in model with a prismatic joint")
    k = int(np.flatnonzero(scara.prismatic)[0]) + 1
    cols = [f"q{j}[deg]" if j == k else f"q{j}" for j in range(1, scara.n + 1)]
    q = np.zeros((3, scara.n))
    lines = ["pose," + ",".join(cols) + ",x,y,z"] + [
        f"P{i}," + ",".join("0" for _ in cols) + ",1,2,3" for i in range(3)]
    p = tmp_path / "s.csv"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(UnitError, match=f"joint q{k} is prismatic"):
        load_measurements(p, scara)
    del q


def test_what_cannot_be_told_is_not_refused():
    small_deg = np.array([[1.0, -2.0, 3.0], [0.5, 0.2, -0.1], [2.0, 1.0, 0.0]])
    # degrees that stay within one turn read as rad: cannot be told (documented)
    assert np.array_equal(joint_values_to_rad(small_deg, [1, 1, 1], "rad", src="t"), small_deg)
    # radians in degrees: fewer rows than RADIAN_LOOK_ROWS, or all below RADIAN_LOOK_MIN
    few = Q_RAD[: RADIAN_LOOK_ROWS - 1, :3]
    assert np.allclose(joint_values_to_rad(few, [1, 1, 1], "deg", src="t"), np.radians(few))
    tiny = np.full((5, 3), RADIAN_LOOK_MIN * 0.9)
    assert np.allclose(joint_values_to_rad(tiny, [1, 1, 1], "deg", src="t"), np.radians(tiny))


def test_a_joint_whose_limits_pass_one_turn_takes_them():
    q = np.array([[7.0, 0.0], [-7.5, 0.0]])
    assert np.array_equal(joint_values_to_rad(q, [1, 1], "rad", src="t", bounds=[8.0, 0.0]), q)
    with pytest.raises(UnitError, match=r"column q1 is -7\.5"):
        joint_values_to_rad(q, [1, 1], "rad", src="t", bounds=[7.2, 0.0])


def _targets(tmp_path, q, cols=None):
    cols = cols or [f"q{k}" for k in range(1, 7)]
    lines = ["target," + ",".join(cols)] + [f"T{i}," + ",".join(map(repr, map(float, r)))
                                            for i, r in enumerate(q)]
    p = tmp_path / "t.csv"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_compensate_seeds_in_degrees_are_refused(tmp_path):
    """Issue: seeds in degrees wrote q1 = 93.96 rad with converged=1."""
    with pytest.raises(UnitError, match=r"column q2 is -22.9.*looks like degrees"):
        load_targets(_targets(tmp_path, np.degrees(Q_RAD)), 6, model=PUMA)
    with pytest.raises(UnitError, match="radians in a degree column"):
        load_targets(_targets(tmp_path, Q_RAD), 6, deg=True, model=PUMA)
    tg = load_targets(_targets(tmp_path, np.degrees(Q_RAD), [f"q{k}[deg]" for k in range(1, 7)]),
                      6, model=PUMA)
    assert np.allclose(tg.q, Q_RAD, atol=1e-12)


def test_joint_trajectory_and_motion_csv(tmp_path):
    p = tmp_path / "j.csv"
    p.write_text("t,q1,q2,q3,q4,q5,q6\n" + "".join(
        f"{i},{','.join(map(repr, map(float, r)))}\n" for i, r in enumerate(Q_RAD)))
    with pytest.raises(UnitError, match="radians in a degree column"):
        load_joint_csv(p, PUMA, deg=True)
    assert np.allclose(load_joint_csv(p, PUMA).q, Q_RAD)
    m = tmp_path / "motion.csv"
    m.write_text("t,point,q1,q2,q3,q4,q5,q6,x,y,z\n" + "".join(
        f"{0.01 * i},a,{','.join(map(repr, map(float, r)))},1,2,3\n"
        for i, r in enumerate(np.degrees(Q_RAD))))
    with pytest.raises(UnitError, match="looks like degrees"):
        load_trajectory(m, PUMA)


def test_command_line_typed_angles(capsys):
    assert main(["fk", "--q", "10", "-20", "30", "5", "45", "15"]) == 2
    err = capsys.readouterr().err
    assert "--q: q1 is 10" in err and "--deg" in err and "Traceback" not in err
    assert main(["fk", "--deg", "--q", "10", "-20", "30", "5", "45", "15", "--json"]) == 0
    deg = json.loads(capsys.readouterr().out)
    rad = [repr(float(v)) for v in np.radians([10, -20, 30, 5, 45, 15])]
    assert main(["fk", "--q", *rad, "--json"]) == 0
    assert np.allclose(deg["position"], json.loads(capsys.readouterr().out)["position"])


def test_command_line_files_round_trip_with_declared_units(tmp_path, capsys):
    out = tmp_path / "m.csv"
    assert main(["measure", "--poses", "8", "--out", str(out), "--deg", "--seed", "1"]) == 0
    header = out.read_text().splitlines()[0]
    assert "q1[deg]" in header
    m = load_measurements(out, PUMA)  # declared: read without deg=True
    assert np.all(np.abs(m.q) < 2 * np.pi)
    capsys.readouterr()
    plan_limits = ",".join(["-165:165"] * 6)
    assert main(["plan", "--model", "puma", "--poses", "10", "--effects", "joint_offset",
                 "--out", str(tmp_path / "p.csv"), f"--limits={plan_limits}"]) == 2
    assert "--limits" in capsys.readouterr().err
