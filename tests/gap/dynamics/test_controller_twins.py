"""The diagnosis on a simulated log with a real controller log's defects (issue 32 part 2):
the UR5e with Coulomb friction hidden on joint 3, simulated at 5 kHz; the clean twin is every
5th sample (1 kHz), the defective twin takes samples 0.8-1.6 ms apart, writes 5 % of its rows
twice, has eight gaps of 2-9 ms and torques quantised to 0.01 N m, in libfranka's names. Both
are read from CSV and diagnosed: the same finding, sizes within each other's interval."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from sim.studies.dynamics.truth import HiddenDynamics, simulate
from tests.gap.dynamics.conftest import UR5E_NOISE
from zrp.gap.dynamics import TorqueLog, load_torque_log, write_torque_log
from zrp.gap.dynamics.diagnosis import diagnose_dynamics


def _defective_rows(n_fine: int, rng) -> np.ndarray:
    """Row indices into a 5 kHz log: steps of 4-8 fine samples (0.8-1.6 ms), eight gaps."""
    rows = np.cumsum(rng.integers(4, 9, n_fine // 4))
    rows = rows[rows < n_fine]
    gaps = np.sort(rng.choice(np.arange(500, rows.size - 500), 8, replace=False))
    for g in gaps:  # 2-9 ms without a sample
        rows[g:] += rng.integers(10, 45)
    return rows[rows < n_fine]


def _franka_csv(log: TorqueLog, rows: np.ndarray, path, rng):
    n = log.n_joints
    head = ["time [ms]", *(f"q_{k}" for k in range(n)), *(f"dq_{k}" for k in range(n)),
            *(f"tau_J_{k}" for k in range(n))]
    tau = np.round(log.tau / 0.01) * 0.01
    out = [",".join(head)]
    for i in rows:
        out.append(",".join(repr(float(v)) for v in [log.t[i] * 1e3, *log.q[i], *log.qd[i],
                                                     *tau[i]]))
        if rng.random() < 0.05:
            out.append(out[-1])
    path.write_text("\n".join(out) + "\n")
    return path


@pytest.mark.slow
def test_defective_twin_gives_the_clean_twins_findings(ur5e, ur5e_command, tmp_path):
    hidden = HiddenDynamics(coulomb=np.array([0, 0, 2.0, 0, 0, 0]))
    fine = simulate(ur5e, hidden, ur5e_command, 14.0, noise_nm=UR5E_NOISE, rate_hz=5000.0,
                    seed=2)
    every5 = np.arange(0, fine.n_samples, 5)
    clean = TorqueLog(fine.t[every5], fine.q[every5], fine.qd[every5], fine.tau[every5])
    rng = np.random.default_rng(5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        clean = load_torque_log(write_torque_log(clean, tmp_path / "clean.csv"))
        bad = load_torque_log(_franka_csv(fine, _defective_rows(fine.n_samples, rng),
                                          tmp_path / "franka.csv", rng))
    assert len(bad.conditioning.gaps) == 8 and bad.conditioning.repeats > 0
    d_clean, d_bad = diagnose_dynamics(ur5e, clean), diagnose_dynamics(ur5e, bad)
    found = [(e.name, e.joint) for e in d_clean.effects]
    assert found[:1] == [("coulomb", 2)]
    assert [(e.name, e.joint) for e in d_bad.effects] == found
    a, b = d_clean.effects[0].params["coulomb"], d_bad.effects[0].params["coulomb"]
    assert b.low <= a.value <= b.high and a.low <= b.value <= a.high
    np.testing.assert_allclose(d_bad.noise_nm, d_clean.noise_nm, rtol=0.1)
    assert np.all(d_bad.rms_after <= 1.5 * d_bad.noise_nm)
    assert any("8 gap(s)" in s for s in d_bad.notes)
    assert any("libfranka" in s for s in d_bad.notes)
