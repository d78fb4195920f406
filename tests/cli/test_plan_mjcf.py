"""``zrp plan --mjcf``: joint compliance planned on the arm's own gravity torques, the basis
``zrp diagnose --mjcf`` fits (issue 23's connected chain). On the UR10 as shipped in
example-robot-data (optional: the tests skip without it)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import zrp
from mjcf.gravity import gravity_torques
from tests.arms import erd_root
from zrp.calibration import design_std
from zrp.calibration.planfile import read_plan
from zrp.cli import main
from zrp.kinematics import forward_kinematics
from zrp.kinematics.sampling import default_limits, uniform_joint_values

POSES = 30


def _ur10(tmp_path, capsys):
    urdf = str(erd_root() / "ur_description" / "urdf" / "ur10_robot.urdf")
    toml = str(tmp_path / "ur10.toml")
    assert main(["import", urdf, "--out", toml]) == 0
    capsys.readouterr()
    return urdf, toml, zrp.load_model(toml)


def _plan(capsys, argv, code=0):
    rc = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == code, err
    return json.loads(out) if code == 0 else err


def test_compliance_is_planned_on_the_arms_gravity_torques(tmp_path, capsys):
    urdf, toml, model = _ur10(tmp_path, capsys)
    floor = -200.0  # mm: keeps the wrist out of the table under the base
    out = tmp_path / "plan.csv"
    res = _plan(capsys, ["plan", "--model", toml, "--poses", str(POSES), "--effects",
                         "joint_compliance", "--mjcf", urdf, "--floor", str(floor),
                         "--candidates", "400", "--out", str(out)])
    std = {p["name"]: p["std"] for p in res["parameters"]}
    units = {p["name"]: p["unit"] for p in res["parameters"]}
    # the diagnosis's MJCF basis (one compliance per joint on its gravity torque), not the
    # lumped-mass weights q2.w_p3.. of a plan without --mjcf
    assert units["q2.compliance"] == "rad/(N m)" and not any(".w_" in n for n in std)
    assert res["gravity_torques"] == urdf
    # joint 6 turns the end point about its own axis: its compliance moves nothing
    assert "q6.compliance" in res["unidentifiable"] and "q6.compliance" not in std
    plan = read_plan(out, model)
    assert np.all(plan.q >= default_limits(model)[:, 0])
    assert np.all(plan.q <= default_limits(model)[:, 1])
    fk = forward_kinematics(model, plan.q)
    assert fk.points[..., 2].min() > floor and fk.position[:, 2].min() > floor

    # The same basis on another design of as many poses (design_std: no exchange involved):
    # the candidates where joint 2 carries the least gravity torque
    names = [j.name for j in model.joints]
    rng = np.random.default_rng(1)
    cand = uniform_joint_values(model, 2000, rng, default_limits(model))
    tau = gravity_torques(urdf, cand, joint_names=names)
    unloaded = np.argsort(np.abs(tau[:, 1]))[:POSES]
    d = np.ones((POSES, model.n))

    def std_of(idx):
        got, s = design_std(model, cand[idx], d, ["joint_compliance"],
                            gravity_torque=tau[idx])
        return dict(zip(got, s, strict=True))["q2.compliance"]

    planned = std["q2.compliance"]
    assert np.isfinite(planned) and planned > 0.0
    assert planned < 0.1 * std_of(unloaded)  # measured: 19x smaller
    # the plan leans on the poses where joint 2 carries much of the arm (measured: mean
    # |tau_2| 80 N m on the plan, 56 N m over random poses in the same limits)
    tau_plan = gravity_torques(urdf, plan.q, joint_names=names)
    assert np.abs(tau_plan[:, 1]).mean() > 1.2 * np.abs(tau[:, 1]).mean()
    # the plan's own prediction, recomputed on the poses it wrote with the file's torques
    got, s = design_std(model, plan.q, plan.direction, ["joint_compliance"],
                        gravity_torque=tau_plan)
    assert np.isclose(dict(zip(got, s, strict=True))["q2.compliance"], planned, rtol=1e-6)


def test_a_file_that_is_not_the_arm_is_named_and_nothing_written(tmp_path, capsys):
    _, toml, _ = _ur10(tmp_path, capsys)
    panda = str(erd_root() / "panda_description" / "urdf" / "panda.urdf")
    out = tmp_path / "plan.csv"
    err = _plan(capsys, ["plan", "--model", toml, "--poses", "20", "--effects",
                         "joint_compliance", "--mjcf", panda, "--out", str(out)], code=2)
    assert "--mjcf" in err and "joint 1" in err and "Traceback" not in err
    assert not out.exists()
    err = _plan(capsys, ["plan", "--model", toml, "--poses", "20", "--effects",
                         "joint_compliance", "--mjcf", str(tmp_path / "none.urdf"),
                         "--out", str(out)], code=2)
    assert "--mjcf" in err and not out.exists()



@pytest.mark.parametrize("effects", [["joint_offset"], ["joint_offset", "link_length"],
                                     ["backlash"], ["joint_offset", "backlash"]])
def test_mjcf_without_joint_compliance_is_refused_by_name(tmp_path, capsys, effects):
    # no effect planned on gravity torques: the file would be read and change nothing (as
    # zrp import --base for an MJCF or zrp diagnose --workers on one file, it is refused)
    xml = tmp_path / "puma.xml"
    assert main(["mjcf", "--model", "puma", "--inertia", "rods", "--out", str(xml)]) == 0
    capsys.readouterr()
    out = tmp_path / "plan.csv"
    argv = ["plan", "--model", "puma", "--poses", "12", "--candidates", "100", "--out",
            str(out), "--mjcf", str(xml), "--effects", *effects]
    err = _plan(capsys, argv, code=2)
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("zrp plan: error: --mjcf: only with joint_compliance in --effects")
    assert f"--effects {' '.join(effects)} uses no torques" in err
    assert not out.exists()
    # with joint_compliance the same file is used: its basis, not the lumped masses'
    res = _plan(capsys, [*argv, "joint_compliance"])
    names = [p["name"] for p in res["parameters"]] + res["unidentifiable"]
    assert "q2.compliance" in names and not any(".w_" in n for n in names)


def test_backlash_is_planned_without_the_torques():
    # why backlash alone does not take --mjcf: its predicted std is the same with any torques
    model = zrp.load_model("puma")
    rng = np.random.default_rng(3)
    q = uniform_joint_values(model, 40, rng, default_limits(model))
    d = rng.choice([-1.0, 1.0], size=q.shape)
    tau = 100.0 * rng.standard_normal(q.shape)  # N m: large enough to set any gravity side
    names, s0 = design_std(model, q, d, ["backlash"])
    names_t, s1 = design_std(model, q, d, ["backlash"], gravity_torque=tau)
    assert names == names_t and any(".backlash" in n for n in names)
    np.testing.assert_array_equal(s0, s1)
