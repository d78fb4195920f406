"""Issue 41 finding 6 (issue 43's "absurd values point at the data"): KUKA A1..A6 written in
radians read as degrees, torques in mN m, a torque frozen for half the log, named effects
that raise the withheld error. Each used to reach the findings (a link 1.3e5 kg heavier,
"+7.9 t", "+136 kg", "-7 % removed"); now a data problem with its likely cause, nothing in
the findings or in corrected.xml."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from zrp.gap.dynamics import load_torque_log
from zrp.gap.dynamics.diagnosis import diagnose_dynamics
from zrp.gap.dynamics.plausible import plausibility
from zrp.gap.dynamics.report import diagnosis_json, report_markdown
from zrp.gap.dynamics.results import FoundEffect, Param
from zrp.gap.dynamics.verdict import headline

N = 6
ZRP_HEAD = ["t [s]", *(f"q{k + 1} [rad]" for k in range(N)),
            *(f"tau{k + 1} [Nm]" for k in range(N))]


@pytest.fixture(scope="module")
def puma_run():
    from mjcf.arm import resolve_arm
    from zrp.gap.dynamics.fourier import random_fourier

    arm = resolve_arm("puma")
    f = random_fourier(np.array([0.0, -0.5, 0.5, 0.0, 0.5, 0.0]), 0.6, 1.0, 3.0, seed=1)
    t = np.arange(4000) * 2e-3
    q, qd, qdd = f.evaluate(t)
    tau = arm.inverse_dynamics(q, qd, qdd) + np.random.default_rng(0).normal(0, 0.02, q.shape)
    return arm, t, q, tau


def _diagnose(arm, tmp_path, head, t, q, tau):
    p = tmp_path / "log.csv"
    rows = np.column_stack([t, q, tau]).tolist()
    p.write_text(",".join(head) + "\n" + "\n".join(",".join(map(repr, r)) for r in rows) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = load_torque_log(p)
        return log, diagnose_dynamics(arm, log)


def _nominal_masses(arm, d):
    import mujoco

    from mjcf.corrected import CorrectedMJCF

    text, _ = CorrectedMJCF(arm).corrected_model(d)
    m = mujoco.MjModel.from_xml_string(text)
    return np.array(m.body_mass), np.array(arm.model.body_mass)


def test_kuka_radians_read_as_degrees_is_a_data_problem(puma_run, tmp_path):
    arm, t, q, tau = puma_run
    head = ["t [s]", *(f"A{k + 1}" for k in range(N)),
            *(f"MeasuredTorque_{k + 1}" for k in range(N))]
    _, d = _diagnose(arm, tmp_path, head, t, q, tau)
    assert d.found == [] and d.bodies == {}
    text = " ".join(d.data_problems)
    assert "not physical for this arm" in text and "radians read as degrees" in text
    assert "write A1 [rad]" in text
    got, nominal = _nominal_masses(arm, d)
    np.testing.assert_allclose(got, nominal)


def test_torques_in_mnm_are_a_data_problem(puma_run, tmp_path):
    arm, t, q, tau = puma_run
    _, d = _diagnose(arm, tmp_path, ZRP_HEAD, t, q, 1000.0 * tau)
    assert d.found == [] and d.bodies == {}
    text = " ".join(d.data_problems)
    assert "mN m read as N m" in text and "kg" in text
    assert "points at a data problem" in headline(d)
    assert "## Data problems" in report_markdown(d) and diagnosis_json(d)["data_problems"]


def test_a_torque_frozen_for_half_the_log_excludes_the_joint_named(puma_run, tmp_path):
    arm, t, q, tau = puma_run
    frozen = tau.copy()
    frozen[2000:, 1] = frozen[2000, 1]
    log, d = _diagnose(arm, tmp_path, ZRP_HEAD, t, q, frozen)
    assert "torque frozen" in log.unmeasured[1] and "50% of the log" in log.unmeasured[1]
    assert not any(abs(b.mass_change) > 1.0 for b in d.bodies.values())


def test_effects_that_raise_the_withheld_error_are_not_findings(puma_run, tmp_path):
    arm, t, q, tau = puma_run
    log, d = _diagnose(arm, tmp_path, ZRP_HEAD, t, q, tau)
    fake = FoundEffect("coulomb1", "coulomb", 0, "", {"coulomb": Param(0.4, 0.3, 0.5, "N m")},
                       5.0, np.full(N, 0.1))
    worse = replace(d, effects=[fake], rms_after=1.07 * np.asarray(d.rms_before))
    out = plausibility(arm, log, worse)
    assert out.found == [] and "raise the withheld error" in out.data_problems[0]
    assert "-7% removed" in out.data_problems[0]


def test_a_plausible_diagnosis_is_left_alone(puma_run, tmp_path):
    arm, t, q, tau = puma_run
    log, d = _diagnose(arm, tmp_path, ZRP_HEAD, t, q, tau)
    assert d.data_problems == [] and plausibility(arm, log, d) is d
