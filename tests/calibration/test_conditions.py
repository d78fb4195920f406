"""The conditions of a calibration are recorded in its files and enforced on requests; nothing
outside its physical domain is written or read; model_file cannot leave the file's folder."""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import json
import warnings

import numpy as np
import pytest

import zrp
from tests.calibration.pairs import write_bound
from zrp.calibration import (
    CalibratedRobot,
    PoseConditions,
    Term,
    compensate_program,
    read_calibration,
    write_calibration,
)
from zrp.calibration.calibrated import rotation_about
from zrp.calibration.conditions import ConditionWarning, MissingConditionError
from zrp.calibration.validation import axis_tilts, validate_calibration
from zrp.cli.app import main
from zrp.errors import InputError
from zrp.gap import Injection, synthesize
from zrp.gap.model.domains import ImplausibleValueError
from zrp.kinematics import uniform_joint_values
from zrp.model.files import dumps_model

PUMA = zrp.load_model("puma")
LIMITS = [(-2.8, 2.8), (-2.0, 2.0), (-2.5, 2.5), (-3.0, 3.0), (-2.0, 2.0), (-3.1, 3.1)]


def _arm_with_limits() -> zrp.Manipulator:
    return zrp.Manipulator.from_arrays(
        PUMA.axes, PUMA.bodies, axial=PUMA.end_effector.axial,
        transverse=PUMA.end_effector.transverse, name="puma with limits",
        length_unit=PUMA.length_unit, joint_names=[f"j{k}" for k in range(1, 7)],
        limits=LIMITS)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A geometric calibration of an arm with joint limits, from data with a load and a temp
    column, through the command line (data file hash, degrees, instrument)."""
    model = _arm_with_limits()
    rng = np.random.default_rng(5)
    q = uniform_joint_values(model, 80, rng, np.array(LIMITS) * 0.9)
    meas = synthesize(model, q, Injection(joint_offset={2: 1e-3, 3: -8e-4}), rng=rng)
    pose = meas.pose_index
    meas = dataclasses.replace(meas, load=np.where(pose % 2 == 0, 0.0, 5.0),
                               temp=20.0 + (pose % 7))
    root = tmp_path_factory.mktemp("cond")
    (root / "arm.toml").write_text(dumps_model(model))
    meas.to_csv(root / "d.csv", deg=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main(["calibrate", "--model", str(root / "arm.toml"), "--data",
                   str(root / "d.csv"), "--deg", "--out", str(root / "out"), "--effects",
                   "joint_offset", "--instrument", "Leica AT960"])
    assert rc == 0
    return root


def test_conditions_are_in_both_files(run):
    doc = json.loads((run / "out" / "compensation.json").read_text())
    c = doc["conditions"]
    assert c["payloads_kg"] == [0.0, 5.0]
    assert c["temp_range_degC"] == [20.0, 26.0]
    assert c["tool_points"] == ["s1", "s2", "s3"]
    assert c["length_unit"] == "mm" and c["angle_unit"] == "rad"
    assert c["data_angle_unit"] == "deg" and c["instrument"] == "Leica AT960"
    assert c["data_file"] == "d.csv"
    assert c["data_sha256"] == hashlib.sha256((run / "d.csv").read_bytes()).hexdigest()
    assert c["software"] == f"zrp-accuracy {zrp.__version__}"
    assert c["joint_limits"] == [list(v) for v in LIMITS]
    toml = (run / "out" / "calibrated.toml").read_text()
    assert c["data_sha256"] in toml and "payloads_kg = [0.0, 5.0]" in toml
    # the calibrated model keeps the original's joint limits and names
    model = zrp.load_model(run / "out" / "calibrated.toml")
    assert [j.limits for j in model.joints] == LIMITS
    assert model.joint_names == tuple(f"j{k}" for k in range(1, 7))
    back = read_calibration(run / "out" / "compensation.json")
    assert back.conditions is not None and back.conditions.payloads_kg == (0.0, 5.0)


def _targets(path, q, ids=None):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["target", *[f"q{k}" for k in range(1, 7)]])
        for i, row in enumerate(q):
            w.writerow([ids[i] if ids else f"T{i}", *row])
    return path


def test_target_outside_a_model_limit_is_named(run, tmp_path, capsys):
    """No --limits: the calibrated model's own limits are enforced on every row."""
    q = np.zeros((3, 6))
    q[1, 2] = 2.8     # rad: beyond joint 3's limit of 2.5 (an angle, so not a unit error)
    t = _targets(tmp_path / "t.csv", q, ["a", "elbow", "c"])
    rc = main(["compensate", "--calibration", str(run / "out" / "compensation.json"),
               "--targets", str(t), "--out", str(tmp_path / "o.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "target elbow: " in err and "joint 3 is 2.8" in err
    assert "outside its limit [-2.5, 2.5]" in err


def _payload_robot(run) -> CalibratedRobot:
    """The run's calibration with a payload-dependent joint-map term (lumped-mass compliance
    under the data's load: w_load)."""
    cal = read_calibration(run / "out" / "compensation.json")
    w_load = Term("q2.w_load", "joint_compliance", 2, "rad/(mm kg)", 2e-7)
    return dataclasses.replace(cal, terms=(*cal.terms, w_load))


def test_payload_omitted_is_refused(run, tmp_path, capsys):
    cal = _payload_robot(run)
    _, c = write_calibration(cal, tmp_path / "c.toml", tmp_path / "c.json")
    t = _targets(tmp_path / "t.csv", np.full((2, 6), 0.3))
    args = ["compensate", "--calibration", str(c), "--targets", str(t), "--out",
            str(tmp_path / "o.csv")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--load" in err and "[0.0, 5.0] kg" in err and "q2.w_load" in err
    assert not (tmp_path / "o.csv").exists()
    assert main([*args, "--load", "5"]) == 0
    # the API warns instead, and says so
    with pytest.warns(ConditionWarning, match="load"):
        compensate_program(cal, np.full((2, 6), 0.3))
    # a payload beyond the measured range is an extrapolation: a warning
    with pytest.warns(ConditionWarning, match=r"payload 9..9 kg is outside the measured "
                      r"range 0..5 kg"):
        compensate_program(cal, np.full((2, 6), 0.3), conditions=PoseConditions(
            load=np.full(2, 9.0)))


def test_thermal_model_without_temperature_is_refused(run, tmp_path, capsys):
    cal = dataclasses.replace(read_calibration(run / "out" / "compensation.json"),
                              kappa=1.2e-5)
    _, c = write_calibration(cal, tmp_path / "c.toml", tmp_path / "c.json")
    t = _targets(tmp_path / "t.csv", np.full((2, 6), 0.3))
    args = ["compensate", "--calibration", str(c), "--targets", str(t), "--out",
            str(tmp_path / "o.csv")]
    assert main(args) == 2 and "--temp" in capsys.readouterr().err
    with pytest.warns(ConditionWarning, match="temperature 60..60 degC is outside"):
        assert main([*args, "--temp", "60"]) == 0


def test_missing_condition_error_is_named():
    from zrp.calibration.conditions import Conditions, missing_conditions

    cond = Conditions((0.0, 5.0), ("s1",), None, "mm", (None,))
    term = Term("q1.compliance", "joint_compliance", 1, "rad/(N m)", 1e-5)
    with pytest.raises(MissingConditionError, match="--load"):
        missing_conditions((term,), "mjcf", 0.0, cond, temp=None, load=None)
    missing_conditions((term,), "mjcf", 0.0, cond, temp=None, load=2.0)
    # data without payloads: nothing to require
    missing_conditions((term,), "mjcf", 0.0, dataclasses.replace(cond, payloads_kg=None),
                       temp=None, load=None)


@pytest.mark.parametrize(("term", "match"), [
    (Term("q3.backlash", "backlash", 3, "rad", -4e-4),
     r"q3.backlash = -0.0004 rad is outside its physical domain 0 <= value <= 0.02 rad"),
    (Term("q2.compliance", "joint_compliance", 2, "rad/(N m)", -1e-6),
     r"q2.compliance = -1e-06 rad/\(N m\) is outside .* 0 <= value"),
    (Term("q6.sin1", "cyclic_error", 6, "rad", 1.04),
     r"q6.amplitude1 .* = 1.04 rad is outside its physical domain 0 <= value <= 0.005"),
])
def test_implausible_values_are_refused_by_the_writer(run, tmp_path, term, match):
    cal = read_calibration(run / "out" / "compensation.json")
    bad = dataclasses.replace(cal, terms=(*cal.terms, term))
    with pytest.raises(ImplausibleValueError, match=match):
        write_calibration(bad, tmp_path / "c.toml", tmp_path / "c.json")
    assert not list(tmp_path.iterdir())
    # nor read back from a file edited by hand
    _, c = write_calibration(cal, tmp_path / "c.toml", tmp_path / "c.json")
    doc = json.loads(c.read_text())
    doc["joint_map"].append(term.to_dict())
    write_bound(c, doc)  # the pair re-bound: the domain check, not the hash, meets the edit
    with pytest.raises(ImplausibleValueError, match=match):
        read_calibration(c)


def test_axis_tilt_is_bounded_unless_widened(run, tmp_path):
    cal = read_calibration(run / "out" / "compensation.json")
    # tilt the (folded) axis of joint 4 by 0.02 rad about a perpendicular direction
    axes = np.array(cal.model.axes)
    perp = np.cross(axes[3], [1.0, 0.0, 0.0])
    axes[3] = rotation_about(perp / np.linalg.norm(perp), 0.02) @ axes[3]
    m = cal.model
    tilted = dataclasses.replace(cal, model=zrp.Manipulator.from_arrays(
        axes, m.bodies, axial=m.end_effector.axial, transverse=m.end_effector.transverse,
        length_unit=m.length_unit, limits=[j.limits for j in m.joints]))
    tilt = axis_tilts(tilted)
    assert tilt[3] == pytest.approx(0.02, abs=1e-4) and tilt[[0, 1, 2, 4, 5]].max() < 1e-6
    with pytest.raises(ImplausibleValueError, match=r"u4.tilt .* = 0.02\d* rad is outside"):
        validate_calibration(tilted)
    validate_calibration(tilted, {"axis_tilt": 0.03})
    wide = dataclasses.replace(tilted, widen={"axis_tilt": 0.03})
    _, c = write_calibration(wide, tmp_path / "c.toml", tmp_path / "c.json")
    assert read_calibration(c).widen == {"axis_tilt": 0.03}
    with pytest.raises(InputError, match="only be widened"):
        validate_calibration(tilted, {"axis_tilt": 0.001})


@pytest.mark.parametrize("model_file", ["../outside.toml", "sub/../../outside.toml",
                                        "/etc/passwd", "", 3])
def test_model_file_cannot_leave_the_folder(run, tmp_path, model_file):
    cal = read_calibration(run / "out" / "compensation.json")
    folder = tmp_path / "calib"
    folder.mkdir()
    _, c = write_calibration(cal, folder / "c.toml", folder / "c.json")
    (tmp_path / "outside.toml").write_text((folder / "c.toml").read_text())
    doc = json.loads(c.read_text())
    doc["model_file"] = model_file
    if model_file == "../outside.toml":  # bound to the file outside: only the path is wrong
        write_bound(c, doc, tmp_path / "outside.toml")
    else:
        c.write_text(json.dumps(doc))
    with pytest.raises(InputError, match="model_file"):
        read_calibration(c)
    if model_file == "../outside.toml":
        assert read_calibration(c, allow_outside=True).n == 6
        assert read_calibration(c, tmp_path / "outside.toml").n == 6


def test_model_file_is_relative_to_the_json(run, tmp_path, monkeypatch):
    cal = read_calibration(run / "out" / "compensation.json")
    (tmp_path / "d" / "models").mkdir(parents=True)
    _, c = write_calibration(cal, tmp_path / "d" / "models" / "m.toml", tmp_path / "d" / "c.json")
    assert json.loads(c.read_text())["model_file"] == "models/m.toml"
    monkeypatch.chdir(tmp_path)     # read from elsewhere: still beside the JSON
    assert read_calibration("d/c.json").n == 6
    with pytest.raises(InputError, match="not in the folder"):
        write_calibration(cal, tmp_path / "m.toml", tmp_path / "d" / "c2.json")
