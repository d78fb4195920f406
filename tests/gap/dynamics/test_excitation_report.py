"""Excitation design within its limits and lowering the regressor's condition number; the
report's files."""

from __future__ import annotations

import numpy as np
import pytest

from sim.studies.dynamics.truth import HiddenDynamics, simulate
from tests.gap.dynamics.conftest import UR5E_NOISE
from zrp.gap.dynamics.diagnosis import diagnose_dynamics
from zrp.gap.dynamics.excitation import condition_number, design_excitation
from zrp.gap.dynamics.fourier import random_fourier
from zrp.gap.dynamics.report import write_report


@pytest.mark.slow
def test_designed_excitation_meets_limits_and_conditions_better(ur5e):
    q0 = np.array([0.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    e = design_excitation(ur5e, q0, 0.5, 1.0, 3.0, torque_limit=60.0, candidates=3,
                          iterations=5, seed=2)
    dq, dqd, dqdd = e.command.peaks()
    assert np.all(dq <= 0.5 + 1e-9) and np.all(dqd <= 1.0 + 1e-9) and np.all(dqdd <= 3 + 1e-9)
    assert np.all(e.peak_torque <= 60.0)
    assert e.kappa <= e.kappa_start < 1e6
    # the same number, recomputed independently of the search
    assert condition_number(ur5e, e.command) == pytest.approx(e.kappa, rel=1e-6)
    # a motion that leaves joint 1 still cannot identify it: infinite kappa
    still = random_fourier(q0, 0.5, 1.0, 3.0, seed=0)
    still.a[0] = 0.0
    still.b[0] = 0.0
    assert condition_number(ur5e, still) == float("inf")


@pytest.mark.slow
def test_report_files(ur5e, ur5e_command, tmp_path):
    log = simulate(ur5e, HiddenDynamics(coulomb=np.array([0, 2.0, 0, 0, 0, 0])), ur5e_command,
                   12.0, noise_nm=UR5E_NOISE, seed=1)
    d = diagnose_dynamics(ur5e, log)
    out = write_report(d, tmp_path / "rep", extra={"sections": {"Tracking": ["- x"]}})
    names = {p.name for p in out.iterdir()}
    assert {"report.md", "report.html", "diagnosis.json", "residuals_velocity.png",
            "residuals_position.png"} <= names
    md = (out / "report.md").read_text()
    assert "coulomb (joint 2)" in md and "## Tracking" in md
    assert "data:image/svg+xml;base64," in (out / "report.html").read_text()
    with pytest.raises(Exception, match=r"exist|force"):
        write_report(d, out)
