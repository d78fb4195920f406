"""Thermal compensation (issue 11): the commands for a stated robot temperature put the
synthetic robot (zrp.gap.synthesize, not the calibration code) on its targets; without a
temperature the API warns and the command line refuses."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import CalibratedRobot, PoseConditions, ThermalWarning, compensate
from zrp.calibration.conditions import ConditionWarning
from zrp.calibration.storage import write_calibration
from zrp.cli.app import main
from zrp.gap import Injection, diagnose, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
LIM = np.tile([-2.5, 2.5], (6, 1))
KAPPA = 2.0e-5


@pytest.fixture(scope="module")
def thermal_cal():
    rng = np.random.default_rng(5)
    q = uniform_joint_values(PUMA, 200, rng, LIM)
    temp = np.linspace(20.0, 35.0, len(q))
    meas = synthesize(PUMA, q, Injection(thermal=KAPPA), rng=rng, noise_sigma=0.01, temp=temp)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        diag = diagnose(PUMA, meas, rng=np.random.default_rng(0))
    return CalibratedRobot.from_diagnosis(diag)


def test_commands_at_the_stated_temperature_land_on_the_targets(thermal_cal):
    cal = thermal_cal
    assert cal.kappa == pytest.approx(KAPPA, rel=0.1)
    q = uniform_joint_values(PUMA, 20, np.random.default_rng(8), np.tile([-2.0, 2.0], (6, 1)))
    base = zrp.forward_kinematics(PUMA, q).position          # targets: nominal end points
    hot = np.full(len(q), 40.0)

    def reached(q_cmd):       # the injected robot at 40 degC (end point, base frame)
        m = synthesize(PUMA, q_cmd, Injection(thermal=KAPPA), rng=np.random.default_rng(0),
                       noise_sigma=0.0, tool_offsets=((0.0, 0.0, 0.0),), frame="base",
                       temp=hot)
        return m.xyz

    with pytest.warns(ConditionWarning, match="40..40 degC is outside the measured range"):
        comp = compensate(cal, base, q, conditions=PoseConditions(temp=hot),  # extrapolated
                          accept_flagged=True)  # random targets: some near a singularity
    before = np.linalg.norm(reached(q) - base, axis=1)
    after = np.linalg.norm(reached(comp.q_command) - base, axis=1)
    assert before.mean() > 0.2                   # 20 K x 2e-5 over ~1 m: ~0.4 mm
    assert after.max() < 0.05 * before.mean(), (before.mean(), after.max())
    with pytest.warns(ThermalWarning, match="reference temperature"):
        compensate(cal, base, q, accept_flagged=True)


def test_cli_needs_the_temperature_when_thermal_was_found(thermal_cal, tmp_path, capsys):
    write_calibration(thermal_cal, tmp_path / "c.toml", tmp_path / "c.json")
    q = uniform_joint_values(PUMA, 5, np.random.default_rng(2), np.tile([-2.0, 2.0], (6, 1)))
    lines = ["target," + ",".join(f"q{k}" for k in range(1, 7))]
    lines += [f"t{i}," + ",".join(f"{v:.6f}" for v in row) for i, row in enumerate(q)]
    (tmp_path / "t.csv").write_text("\n".join(lines) + "\n")
    args = ["compensate", "--calibration", str(tmp_path / "c.json"), "--targets",
            str(tmp_path / "t.csv"), "--out", str(tmp_path / "cmd.csv"), "--accept-flagged"]
    assert main(args) == 2
    assert "--temp" in capsys.readouterr().err
    assert main([*args, "--temp", "30"]) == 0
    assert (tmp_path / "cmd.csv").exists()
