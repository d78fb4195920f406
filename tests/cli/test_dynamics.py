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
    bad.write_text("t,q1,q2,tau1,tau2\n0,0,0,0,0\n")
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
