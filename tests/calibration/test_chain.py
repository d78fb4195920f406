"""The whole calibration chain from the command line on arms shipped as URDFs that no code
here describes (example-robot-data): import -> plan -> measure --poses plan.csv -> diagnose
-> calibrate -> export -> compensate -> verify, each step reading the previous step's file as
written. It ends when the compensated program, commanded on the simulated robot, misses its
targets by at most 1.5x the tracker's pure noise.

The simulated robot is the arm as itself: `zrp measure --arm URDF` gives it the inertias,
damping, friction and tool of the shipped URDF, and `zrp verify` rebuilds that same robot from
the truth file (which names the URDF and its SHA-256); diagnose, calibrate and compensate get the
same URDF's gravity torques (--mjcf). The hidden effects are geometric (joint offsets and a link
length) on three joints.
Pinocchio and example-robot-data are optional: the test skips without them."""

from __future__ import annotations

import csv
import json
import os

import numpy as np
import pytest

import zrp
from tests.arms import erd_root
from zrp.cli import main

ARMS = {  # folder, file in example-robot-data's robots/, and the import's options
    "ur10": ("ur_description", "ur10_robot.urdf", []),
    "xarm7": ("xarm_description", "xarm7.urdf", []),
    "panda": ("panda_description", "panda.urdf", ["--end", "panda_hand_tcp"]),
}
HIDDEN = ["joint_offset:2=0.5mrad", "joint_offset:3=-0.4mrad", "link_length:3=0.1,0.2,-0.1mm"]
RATIO = 1.5


def _run(capsys, argv):
    rc = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return json.loads(out)


@pytest.mark.slow
@pytest.mark.parametrize("arm", sorted(ARMS))
def test_plan_to_verify_on_an_unseen_urdf(tmp_path, capsys, arm):
    folder, name, options = ARMS[arm]
    urdf = os.path.join(erd_root(), folder, "urdf", name)
    model_file = str(tmp_path / f"{arm}.toml")
    _run(capsys, ["import", urdf, *options, "--out", model_file])
    model = zrp.load_model(model_file)

    plan = _run(capsys, ["plan", "--model", model_file, "--poses", "40", "--effects",
                         "joint_offset", "link_length", "--out", str(tmp_path / "plan.csv")])
    with open(tmp_path / "plan.csv") as fh:
        q_plan = np.array([[float(r[f"q{k}"]) for k in range(1, model.n + 1)]
                           for r in csv.DictReader(fh)])
    assert np.all(q_plan >= model.lower) and np.all(q_plan <= model.upper)  # within limits
    assert all(p["std"] < 1.0 for p in plan["parameters"])  # none unidentifiable left in

    hidden = [a for spec in HIDDEN for a in ("--effect", spec)]
    meas = _run(capsys, ["measure", "--model", model_file, "--poses", str(tmp_path / "plan.csv"),
                         "--arm", urdf, *hidden, "--out", str(tmp_path / "meas.csv"),
                         "--seed", "3"])
    assert meas["poses"] == 40 and meas["trajectory"] == "plan"
    build = json.loads((tmp_path / "meas.truth.json").read_text())["robot"]
    assert build["inertia"] == "own" and build["arm_file"] == os.path.abspath(urdf)
    diag = _run(capsys, ["diagnose", "--model", model_file, "--data",
                         str(tmp_path / "meas.csv"), "--mjcf", urdf, "--out",
                         str(tmp_path / "diag"), "--no-plots"])
    _run(capsys, ["calibrate", "--model", model_file, "--data", str(tmp_path / "meas.csv"),
                  "--mjcf", urdf, "--out", str(tmp_path / "cal")])
    cal_toml = str(tmp_path / "cal" / "calibrated.toml")
    _run(capsys, ["export", "--model", cal_toml, "--to", "urdf",
                  "--out", str(tmp_path / "calibrated.urdf")])
    assert (tmp_path / "calibrated.urdf").read_text().startswith("<")

    rng = np.random.default_rng(7)
    program = zrp.reachable_poses(model, 16, rng)
    with open(tmp_path / "program.csv", "w") as fh:
        fh.write("target," + ",".join(f"q{k}" for k in range(1, model.n + 1)) + "\n")
        for i, row in enumerate(program):
            fh.write(f"T{i + 1}," + ",".join(repr(float(v)) for v in row) + "\n")
    comp_json = str(tmp_path / "cal" / "compensation.json")
    comp = _run(capsys, ["compensate", "--calibration", comp_json, "--targets",
                         str(tmp_path / "program.csv"), "--mjcf", urdf,
                         "--out", str(tmp_path / "cmd.csv")])
    assert comp["not_converged"] == 0
    res = _run(capsys, ["verify", "--calibration", comp_json, "--truth",
                        str(tmp_path / "meas.truth.json"), "--targets",
                        str(tmp_path / "program.csv"), "--commands", str(tmp_path / "cmd.csv")])
    print(f"{arm} ({', '.join(diag['effects'])}): {res['rms_before']:.4g} -> "
          f"{res['rms_after']:.4g} {model.length_unit} "
          f"({res['ratio_after_to_noise']:.2f}x the noise)")
    assert res["rms_before"] > 5 * res["noise_rms"]  # the hidden effects show as programmed
    assert res["ratio_after_to_noise"] <= RATIO, res
