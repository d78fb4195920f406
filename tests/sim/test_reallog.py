"""The real-looking controller logs of the dynamic gap's benchmark: each defect as specified
(issue 32: steps of 0.8-1.6 ms around 1 ms, 5 % repeated rows, eight gaps of 2-9 ms,
quantisation, a ripple locked to the joint position, a controller's own names), the absent
hand's truth against the URDF's own masses, and a scenario's truth never reaching the
diagnosis."""

from __future__ import annotations

import builtins
import io
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from sim.studies.dynamics.logprep import prepare_by_hand
from sim.studies.dynamics.reallog import (
    LogDefects,
    controller_log,
    log_times,
    write_controller_log,
)
from zrp.gap.dynamics.data import TorqueLog, load_torque_log


def _clean(seconds: float = 4.0, n: int = 3) -> TorqueLog:
    """A smooth 1 kHz log: q_k = 0.5 sin((k + 1) t), qd its derivative, tau = 2 q."""
    t = np.arange(0.0, seconds + 1e-9, 1e-3)
    w = np.arange(1, n + 1)
    q = 0.5 * np.sin(np.outer(t, w))
    qd = 0.5 * np.cos(np.outer(t, w)) * w
    return TorqueLog(t, q, qd, 2.0 * q)


def test_clock_jitter_and_gaps_as_specified():
    d = LogDefects(jitter=True, gaps=8)
    t = log_times(0.0, 20.0, d, np.random.default_rng(3))
    dt = np.diff(t)
    gaps = dt > 1.6e-3 + 1e-12
    assert gaps.sum() == 8
    assert np.all((dt[gaps] >= 2e-3) & (dt[gaps] <= 9e-3))
    steady = dt[~gaps]
    assert steady.min() >= 0.8e-3 - 1e-12 and steady.max() <= 1.6e-3 + 1e-12
    assert abs(np.median(steady) - 1e-3) < 0.05e-3
    assert steady.std() > 0.05e-3  # it does jitter
    assert np.mean(steady > 1.2e-3) > 0.01  # and some ticks are late


def test_repeated_rows_and_quantisation():
    d = LogDefects(repeat_share=0.05, torque_lsb_nm=0.02, encoder_lsb_rad=1e-4)
    log = controller_log(_clean(), np.full(3, 0.01), d, seed=1)
    same = np.all(np.diff(np.column_stack([log.t, log.q, log.qd, log.tau]), axis=0) == 0.0,
                  axis=1)
    assert same.sum() == log.repeated_rows.size
    assert abs(same.sum() / log.t.size - 0.05) < 0.002
    assert np.array_equal(np.flatnonzero(same) + 1, log.repeated_rows)
    assert np.allclose(log.tau / 0.02, np.round(log.tau / 0.02), atol=1e-9)
    assert np.allclose(log.q / 1e-4, np.round(log.q / 1e-4), atol=1e-9)


def test_ripple_is_locked_to_the_joint_position():
    sigma = np.array([0.1, 0.2, 0.05])
    d = LogDefects(ripple_sigma=1.5, ripple_order=16.0)
    clean = _clean()
    log = controller_log(clean, sigma, d, seed=2, encoder_noise_rad=0.0)
    r = log.tau - 2.0 * log.q  # the ripple plus the noise
    for k in range(3):
        a = np.column_stack([np.sin(16.0 * log.q[:, k]), np.cos(16.0 * log.q[:, k])])
        coef, *_ = np.linalg.lstsq(a, r[:, k], rcond=None)
        assert np.hypot(*coef) == pytest.approx(1.5 * sigma[k], rel=0.05)
        assert np.std(r[:, k] - a @ coef) == pytest.approx(sigma[k], rel=0.05)


def test_names_and_reading(tmp_path):
    clean = _clean()
    plain = controller_log(clean, np.full(3, 0.01), LogDefects(), seed=1)
    path = write_controller_log(plain, tmp_path / "std.csv")
    read = load_torque_log(path, n_joints=3)  # the standard form reads as is
    assert np.allclose(read.tau, plain.tau) and np.allclose(read.t, plain.t)

    real = controller_log(clean, np.full(3, 0.01), LogDefects.real("rtde"), seed=1)
    kt = np.array([10.0, 8.0, 4.0])
    path = write_controller_log(real, tmp_path / "rtde.csv", torque_constant=kt)
    header = path.read_text(encoding="utf-8").splitlines()[0].split(",")
    assert header[:2] == ["timestamp", "actual_q_0"] and header[-1] == "actual_current_2"
    a = np.loadtxt(path, delimiter=",", skiprows=1, comments="#")
    assert np.allclose(a[:, 7:] * kt, real.tau)
    franka = controller_log(clean, np.full(3, 0.01), LogDefects.real("franka"), seed=1)
    header = write_controller_log(franka, tmp_path / "f.csv").read_text(
        encoding="utf-8").splitlines()[0].split(",")
    assert header[:2] == ["time", "q_0"] and header[4] == "dq_0" and header[-1] == "tau_J_2"

    prepared, done = prepare_by_hand(path)  # as a user does by hand today
    assert any("repeat" in s for s in done) and any("resampled" in s for s in done)
    dt = np.diff(prepared.t)
    assert np.ptp(dt) < 1e-9
    inner = (prepared.t > 0.1) & (prepared.t < 3.9)
    exact = 0.5 * np.sin(np.outer(prepared.t[inner], [1, 2, 3]))
    assert np.max(np.abs(prepared.q[inner] - exact)) < 1e-3


def _urdf_mass(path: Path, links: set[str]) -> float:
    root = ET.parse(path).getroot()
    return sum(float(link.find("inertial/mass").get("value")) for link in root.iter("link")
               if link.get("name") in links and link.find("inertial/mass") is not None)


def test_absent_hand_truth_is_the_urdf_hand():
    pytest.importorskip("pinocchio", reason="optional: pip install pin")
    from sim.studies.dynamics.realscenarios import REAL_ARMS, RealScenario, draw_truth, erd_file

    real = REAL_ARMS["panda"]
    arm = real.load()
    hidden, _, desc = draw_truth(RealScenario("panda", "hand", 1), arm)
    hand = _urdf_mass(erd_file(real.urdf), {"panda_hand", "panda_leftfinger", "panda_rightfinger"})
    assert desc["hand"]["hand_kg"] == pytest.approx(hand, rel=1e-9)
    (b, dphi), = hidden.inertial.items()
    assert b == arm.tool_body and dphi[0] == pytest.approx(-hand)


@pytest.mark.slow
def test_truth_never_reaches_the_diagnosis(tmp_path, monkeypatch):
    from sim.studies.dynamics import realbench as rb
    from sim.studies.dynamics.realscenarios import RealScenario

    sc = RealScenario("puma", "gravity+friction", 2, 6.0, LogDefects.real("franka"))
    csv, _, truth = rb.simulate_real(sc, tmp_path / "logs", tmp_path / "truth")
    opened: list[Path] = []
    real_open, real_io_open = builtins.open, io.open

    def spy(file, *a, **kw):
        if isinstance(file, (str, Path)):
            opened.append(Path(file).resolve())
        return real_open(file, *a, **kw)

    monkeypatch.setattr(builtins, "open", spy)
    monkeypatch.setattr(io, "open", spy)
    before, how = rb.diagnose_real(csv, "puma")
    monkeypatch.setattr(builtins, "open", real_open)
    monkeypatch.setattr(io, "open", real_io_open)
    assert csv.resolve() in opened
    assert not any(p.name.endswith(".truth.json") or (tmp_path / "truth") in p.parents
                   for p in opened)
    truth.unlink()
    after, how_after = rb.diagnose_real(csv, "puma")
    assert how == how_after
    assert [e.key for e in before.effects] == [e.key for e in after.effects]
    assert np.array_equal(before.rms_after, after.rms_after)
