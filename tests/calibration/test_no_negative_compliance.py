"""No negative compliance reaches a file (issue 33): data whose unconstrained lumped-mass fit
wants joint 2's weights to sum below 0 (a joint deflecting against its load) give a
calibration with them held at sum 0 (issue 34: the least-squares answer on the domain's
bound, not every weight taken out), with the reason noted in compensation.json; the writer
refuses a negative sum built by hand."""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import (
    CalibrationOptions,
    calibrate,
    read_calibration,
    write_calibration,
)
from zrp.calibration.jointmap import Term
from zrp.gap import Injection, synthesize
from zrp.gap.fit.leastsq import fit
from zrp.gap.model.domains import SUM_RTOL, ImplausibleValueError, sum_inside
from zrp.gap.model.effects import effect_parameters
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


def test_negative_lumped_compliance_never_written(tmp_path):
    rng = np.random.default_rng(7)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 150, rng),
                      Injection(compliance={2: -4e-5}, masses={"ee": 5.0}), rng=rng,
                      noise_sigma=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = calibrate(PUMA, meas, options=CalibrationOptions(
            effects=("joint_compliance", "joint_offset")))
    d = result.diagnosis
    ctx, reg = d.context, d.nominal_fit
    specs, _ = effect_parameters(ctx, "joint_compliance")
    free = fit(ctx, list(reg.specs) + specs, d.fitting_poses,
               np.concatenate([reg.theta, np.zeros(len(specs))]), reg.base_rotation)
    wants = {s.name: v for s, v in zip(free.specs, free.theta, strict=True)
             if s.name.startswith("q2.w_")}
    assert math.fsum(wants.values()) < -1e-6  # the unconstrained fit wants a negative sum
    result.write(tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    doc = json.loads((tmp_path / "compensation.json").read_text(encoding="utf-8"))
    comp = [t["value"] for t in doc["joint_map"] if t["name"].startswith("q2.w_")]
    assert len(comp) == len(wants) > 1  # held at sum 0, the weights otherwise free
    assert sum_inside(comp) and abs(math.fsum(comp)) <= SUM_RTOL * math.fsum(map(abs, comp))
    assert max(map(abs, comp)) > 1e-7  # not all taken out (nominal 0)
    assert any("q2 lumped weights held at sum 0" in n for n in doc["taken_out_non_physical"])
    back = read_calibration(tmp_path / "compensation.json")  # validated again on reading
    assert [t.value for t in back.terms if t.name.startswith("q2.w_")] == comp
    assert "TAKEN OUT as non-physical" in (tmp_path / "calibrated.toml").read_text()
    bad = dataclasses.replace(result.robot, terms=(
        Term("q2.w_ee", "joint_compliance", 2, "rad/mm", -1.5e-6),))
    with pytest.raises(ImplausibleValueError, match=r"q2\.w_ee"):
        write_calibration(bad, tmp_path / "b" / "c.toml", tmp_path / "b" / "c.json")


def test_one_negative_weight_with_a_positive_sum_is_written(tmp_path):
    """A centre of mass behind a joint is lumped with a negative weight on a point ahead of
    it: the file keeps it (the joint's weights sum to its compliance times a positive mass)."""
    rng = np.random.default_rng(3)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 60, rng), Injection(), rng=rng,
                      noise_sigma=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = calibrate(PUMA, meas, options=CalibrationOptions(effects=("joint_offset",)))
    ok = dataclasses.replace(result.robot, terms=(
        Term("q2.w_p3", "joint_compliance", 2, "rad/mm", 1e-5),
        Term("q2.w_ee", "joint_compliance", 2, "rad/mm", -2e-6)))
    write_calibration(ok, tmp_path / "c.toml", tmp_path / "c.json")
    doc = json.loads((tmp_path / "c.json").read_text(encoding="utf-8"))
    assert [t["value"] for t in doc["joint_map"]] == [1e-5, -2e-6]
    bad = dataclasses.replace(ok, terms=(
        Term("q2.w_p3", "joint_compliance", 2, "rad/mm", 1e-6),
        Term("q2.w_ee", "joint_compliance", 2, "rad/mm", -2e-6)))
    with pytest.raises(ImplausibleValueError, match=r"sum of joint 2's lumped weights"):
        write_calibration(bad, tmp_path / "b" / "c.toml", tmp_path / "b" / "c.json")
