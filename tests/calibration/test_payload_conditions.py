"""Conditions that hold (issue 33): a model identified at one payload, never varied, and
without the MJCF's masses holds at that payload only: ``zrp compensate`` refuses another
``--load`` and a missing one (named errors), the API refuses another payload; a model whose
data separated the payload's effect (several payloads, or --mjcf) takes any payload."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import PoseConditions, compensate_program, read_calibration
from zrp.calibration.conditions import (
    MissingConditionError,
    PayloadConditionError,
    check_payload,
    payload_separated,
)
from zrp.cli.app import main
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


@pytest.fixture(scope="module")
def five_kg(tmp_path_factory):
    """A calibration from data with 5 kg on the tool in every pose (lumped masses)."""
    rng = np.random.default_rng(7)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 80, rng),
                      Injection(joint_offset={2: 1e-3}), rng=rng)
    meas = dataclasses.replace(meas, load=np.full(meas.n_rows, 5.0))
    root = tmp_path_factory.mktemp("pay")
    meas.to_csv(root / "d.csv", deg=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["calibrate", "--model", "puma", "--data", str(root / "d.csv"), "--deg",
                     "--effects", "joint_offset", "--no-progress",
                     "--out", str(root / "out")]) == 0
    prog = root / "prog.csv"
    prog.write_text("target,q1,q2,q3,q4,q5,q6\nT0,10,20,-30,5,40,0\nT1,-5,30,-20,0,30,10\n",
                    encoding="utf-8")
    return root


def _compensate(root, tmp_path, *extra: str) -> int:
    return main(["compensate", "--calibration", str(root / "out" / "compensation.json"),
                 "--targets", str(root / "prog.csv"), "--deg",
                 "--out", str(tmp_path / "cmd.csv"), *extra])


def test_one_payload_refuses_another_and_a_missing_one(five_kg, tmp_path, capsys):
    cal = read_calibration(five_kg / "out" / "compensation.json")
    assert cal.conditions.payloads_kg == (5.0,) and not payload_separated(
        cal.conditions, cal.compliance_model)
    assert _compensate(five_kg, tmp_path, "--load", "0") == 2
    err = capsys.readouterr().err
    assert "--load 0: the calibration holds at one payload only" in err and "5 kg" in err
    assert _compensate(five_kg, tmp_path) == 2
    assert "--load: the calibration was identified with a payload of 5 kg" in (
        capsys.readouterr().err)
    assert not (tmp_path / "cmd.csv").exists()
    assert _compensate(five_kg, tmp_path, "--load", "5") == 0
    # the API refuses another payload too, and takes a missing one as the model's own
    q = np.radians([[10, 20, -30, 5, 40, 0]])
    with pytest.raises(PayloadConditionError, match="cannot predict 2 kg"):
        compensate_program(cal, q, conditions=PoseConditions(load=np.full(1, 2.0)))
    compensate_program(cal, q)


def test_separated_payloads_are_taken(five_kg):
    cal = read_calibration(five_kg / "out" / "compensation.json")
    several = dataclasses.replace(cal.conditions, payloads_kg=(0.0, 5.0))
    assert payload_separated(several, "lumped_masses")
    check_payload(several, "lumped_masses", 2.0, required=True)
    assert payload_separated(cal.conditions, "mjcf")
    check_payload(cal.conditions, "mjcf", 2.0, required=True)
    # data without a load column: no payload was recorded, so only "none" is predicted
    unknown = dataclasses.replace(cal.conditions, payloads_kg=None)
    check_payload(unknown, "lumped_masses", None, required=True)
    check_payload(unknown, "lumped_masses", 0.0, required=True)
    with pytest.raises(PayloadConditionError, match="no payload was recorded"):
        check_payload(unknown, "lumped_masses", 3.0, required=True)
    with pytest.raises(MissingConditionError, match="--load"):
        check_payload(cal.conditions, "lumped_masses", None, required=True)
