"""One calibration recipe (issue 33): ``zrp calibrate``, the notebooks and the studies build
the calibrated robot through :func:`zrp.calibration.calibrate`, so the same data give the same
files byte for byte; a calibration identified with --mjcf names the option it needs."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import zrp
from tests.calibration.pairs import write_bound
from zrp.calibration import CalibrationOptions, calibrate
from zrp.cli.app import main
from zrp.gap import Injection, load_measurements, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
ROOT = Path(__file__).resolve().parents[2]
FILES = ("calibrated.toml", "compensation.json")


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> Path:
    rng = np.random.default_rng(5)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 120, rng),
                      Injection(joint_offset={2: 1e-3}, backlash={3: 6e-4}), rng=rng,
                      noise_sigma=0.02)
    root = tmp_path_factory.mktemp("recipe")
    meas.to_csv(root / "d.csv", deg=True)
    return root / "d.csv"


def test_the_command_line_and_the_library_write_the_same_bytes(data, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", "puma", "--data", str(data), "--deg",
                     "--no-progress", "--out", str(tmp_path / "cli")]) == 0
        meas = load_measurements(data, PUMA, deg=True)
        result = calibrate(PUMA, meas, options=CalibrationOptions(
            data_path=str(data), data_angle_unit="deg"))
    result.write(tmp_path / "lib" / FILES[0], tmp_path / "lib" / FILES[1])
    for name in FILES:
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "lib" / name).read_bytes()
    # the recipe's robot is the one written, and it records where the data came from
    doc = json.loads((tmp_path / "lib" / FILES[1]).read_text(encoding="utf-8"))
    assert doc["conditions"]["data_file"] == "d.csv"


#: callers that must build the calibrated robot through the recipe
CALLERS = ("zrp/cli/commands", "sim/lessons/notebooks", "sim/studies")


def test_no_caller_builds_a_calibrated_robot_beside_the_recipe():
    """A call of ``from_diagnosis`` outside the library builds another robot than the
    recipe's (the registration-only baseline is a different thing and may be built)."""
    found = []
    for folder in CALLERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if re.search(r"from_diagnosis\(", line) and "registration_only" not in line:
                    found.append(f"{path.relative_to(ROOT)}:{i}")
    assert found == []
    uses = [p for f in CALLERS for p in (ROOT / f).rglob("*.py")
            if "calibrate(" in p.read_text(encoding="utf-8")]
    assert {p.name for p in uses} >= {"calibrate.py", "04_sim_to_real_gap.py",
                                      "compensation_check.py"}


def test_a_forgotten_mjcf_is_named(data, tmp_path, capsys):
    """A calibration whose compliance came from the MJCF's torques, compensated without
    --mjcf: a named error, not an unknown term."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", "puma", "--data", str(data), "--deg",
                     "--no-progress", "--out", str(tmp_path / "cal")]) == 0
    comp = tmp_path / "cal" / FILES[1]
    doc = json.loads(comp.read_text(encoding="utf-8"))
    doc["compliance_model"] = "mjcf"
    doc["joint_map"].append({"name": "q2.compliance_payload", "effect": "joint_compliance",
                             "joint": 2, "unit": "rad/(N m)", "value": 1e-5, "stderr": 0.0})
    write_bound(comp, doc)  # the pair re-bound: the check meets the edit, not the hash
    prog = tmp_path / "prog.csv"
    prog.write_text("target,q1,q2,q3,q4,q5,q6\nT0,10,20,-30,5,40,0\n", encoding="utf-8")
    rc = main(["compensate", "--calibration", str(comp), "--targets", str(prog), "--deg",
               "--out", str(tmp_path / "cmd.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "this calibration used --mjcf" in err, err
    assert "unknown joint-correction term" not in err
