"""Faithful exports (issue 33): ``zrp export --model calibrated.toml`` would drop the joint-map
terms (cyclic error, backlash...) that live in the compensation file, so it refuses and names
the form that keeps them (--calibration, which writes them to a side file); limited revolute
joints stay ``revolute``; the robot's name is a valid XML name."""

from __future__ import annotations

import dataclasses
import json
import re
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import Term, read_calibration, write_calibration
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.model.files import dumps_model
from zrp.model.urdf import import_urdf
from zrp.model.urdf_writer import robot_name

PUMA = zrp.load_model("puma")
LIMITS = [(-2.8, 2.8), (-2.0, 2.0), (-2.5, 2.5), (-3.0, 3.0), (-2.0, 2.0), (-3.1, 3.1)]
#: an XML Name (ASCII): what a URDF robot name must be
XML_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*$")


@pytest.fixture(scope="module")
def with_terms(tmp_path_factory):
    """A calibration of a limited arm named with spaces and parentheses, with a cyclic error
    and a backlash term in its joint map."""
    model = zrp.Manipulator.from_arrays(
        PUMA.axes, PUMA.bodies, axial=PUMA.end_effector.axial,
        transverse=PUMA.end_effector.transverse, name="ABB IRB 120 (nominal)",
        length_unit=PUMA.length_unit, limits=LIMITS)
    root = tmp_path_factory.mktemp("export")
    (root / "arm.toml").write_text(dumps_model(model))
    rng = np.random.default_rng(3)
    q = uniform_joint_values(model, 80, rng, np.array(LIMITS) * 0.9)
    synthesize(model, q, Injection(joint_offset={2: 1e-3}), rng=rng).to_csv(root / "d.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", str(root / "arm.toml"), "--data",
                     str(root / "d.csv"), "--effects", "joint_offset", "--no-progress",
                     "--out", str(root / "first")]) == 0
    cal = read_calibration(root / "first" / "compensation.json")
    terms = (Term("q2.sin1", "cyclic_error", 2, "rad", 2e-4),
             Term("q3.backlash", "backlash", 3, "rad", 5e-4))
    cal = dataclasses.replace(cal, terms=(*cal.terms, *terms))
    write_calibration(cal, root / "cal" / "calibrated.toml", root / "cal" / "compensation.json")
    return root / "cal"


def test_the_model_form_refuses_and_names_the_form_that_keeps_everything(with_terms, tmp_path,
                                                                         capsys):
    out = tmp_path / "m.urdf"
    rc = main(["export", "--model", str(with_terms / "calibrated.toml"), "--to", "urdf",
               "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and not out.exists()
    assert "cyclic error" in err and "backlash" in err
    assert f"--calibration {with_terms / 'compensation.json'}" in err


def test_the_calibration_form_keeps_terms_joint_types_and_a_valid_name(with_terms, tmp_path):
    out = tmp_path / "m.urdf"
    assert main(["export", "--calibration", str(with_terms / "compensation.json"), "--to",
                 "urdf", "--out", str(out)]) == 0
    side = json.loads((tmp_path / "m.calibration.json").read_text(encoding="utf-8"))
    names = {t["name"] for t in side["joint_map"]}
    assert {"q2.sin1", "q3.backlash"} <= names
    text = out.read_text(encoding="utf-8")
    kinds = re.findall(r'<joint name="[^"]*" type="(\w+)"', text)
    assert kinds.count("revolute") == 6 and "continuous" not in kinds
    name = re.search(r'<robot name="([^"]*)"', text).group(1)
    assert XML_NAME.match(name) and name == "ABB_IRB_120_nominal_calibrated"
    # the URDF reads back with the calibrated geometry and limits
    back = import_urdf(out, end_link="tool").model
    cal = read_calibration(with_terms / "compensation.json")
    assert np.allclose(back.bodies, cal.model.bodies, atol=1e-9)
    assert np.allclose([j.limits for j in back.joints], LIMITS)


@pytest.mark.parametrize(("name", "expected"), [
    ("ABB IRB 120 (calibrated)", "ABB_IRB_120_calibrated"), ("ur10", "ur10"),
    ("3-axis <arm>", "robot_3-axis_arm"), ("", "robot"), ("Größe", "Gr_e")])
def test_robot_names_are_xml_names(name, expected):
    assert robot_name(name) == expected and XML_NAME.match(robot_name(name))
