"""The residual vibration's mode along the path (eq. M6: the arm's own stiffness and damping
from the MJCF) and through the sync delay and servo lag (eq. M7): the kernel against
``scipy.integrate.solve_ivp`` and finite differences, ``mjcf.mode_terms`` against central
differences of ``mj_inverse``, the coupling columns against finite differences, and the MuJoCo
real robot's slow joint-2 mode against both models (the measurement behind eq. M6)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mjcf import MJCFOptions, build, inverse_dynamics_torques, mode_terms
from sim.robot.instrument import Instrument
from sim.robot.motion import MotionEffects, execute_trajectory
from sim.studies.benchmark.motion import MotionScenario, _run_one
from zrp.gap.motion import Trajectory
from zrp.gap.motion.effects import effect_columns, joint_mode, linearise
from zrp.gap.motion.kernels import mode_response
from zrp.gap.motion.paths import exercise_moves


@pytest.fixture(scope="module")
def moves():
    return exercise_moves(np.radians([0, -20, 30, 0, 60, 0]), np.random.default_rng(3),
                          moves=4)


def _ivp(t, f, s, b, omega, zeta):
    def rhs(x, z):
        a, ss, bb = (np.interp(x, t, v) for v in (f, s, b))
        return [z[1], a - (2 * zeta * omega + bb) * z[1] - (omega**2 + ss) * z[0]]
    z0 = [f[0] / (omega**2 + s[0]), 0.0]
    return solve_ivp(rhs, (t[0], t[-1]), z0, t_eval=t, rtol=1e-11, atol=1e-14,
                     max_step=5e-4).y[0]


def test_varying_mode_matches_solve_ivp_and_finite_differences() -> None:
    t = np.arange(0.0, 2.0, 1e-3)
    f = 20.0 * np.sin(3 * t) * (t < 1.0)
    s = 60.0 * np.cos(2 * t)          # 1/s^2, a few % of omega^2
    b = 0.5 * np.sin(5 * t)           # 1/s, comparable with 2 zeta omega = 4
    y, dw, dz = mode_response(t, f, 40.0, 0.05, True, s, b)
    ref = _ivp(t, f, s, b, 40.0, 0.05)
    assert np.max(np.abs(y - ref)) < 2e-5 * np.abs(y).max()
    const = mode_response(t, f, 40.0, 0.05)[0]
    assert np.max(np.abs(const - ref)) > 100 * np.max(np.abs(y - ref))  # the terms matter
    for i, d in enumerate((dw, dz)):
        h = 1e-6
        up, dn = [40.0, 0.05], [40.0, 0.05]
        up[i] += h
        dn[i] -= h
        fd = (mode_response(t, f, *up, False, s, b)[0]
              - mode_response(t, f, *dn, False, s, b)[0]) / (2 * h)
        np.testing.assert_allclose(d, fd, atol=1e-6 * np.abs(d).max())
    # zero terms: the constant-coefficient kernel
    z = np.zeros_like(t)
    np.testing.assert_allclose(mode_response(t, f, 40.0, 0.05, True, z, z)[0], const,
                               atol=1e-12 * np.abs(const).max())


def test_mode_terms_match_central_differences_of_mj_inverse(puma, moves) -> None:
    arm = build(puma, MJCFOptions(inertia="puma560")).model
    t = np.linspace(0.5, moves.duration - 0.5, 7)
    q, qd, qdd = moves(t), moves(t, 1), moves(t, 2)
    terms = mode_terms(arm, q, qd, qdd)
    h = 1e-6
    for k in range(puma.n):
        e = np.zeros(puma.n)
        e[k] = h
        dq = (inverse_dynamics_torques(arm, q + e, qd, qdd)
              - inverse_dynamics_torques(arm, q - e, qd, qdd))[:, k] / (2 * h)
        dv = (inverse_dynamics_torques(arm, q, qd + e, qdd)
              - inverse_dynamics_torques(arm, q, qd - e, qdd))[:, k] / (2 * h)
        mkk = (inverse_dynamics_torques(arm, q, qd, qdd + e)
               - inverse_dynamics_torques(arm, q, qd, qdd - e))[:, k] / (2 * h)
        np.testing.assert_allclose(terms[:, k, 0], dq / mkk, rtol=1e-4, atol=1e-4)
        np.testing.assert_allclose(terms[:, k, 1], dv / mkk, rtol=1e-4, atol=1e-6)
    assert np.abs(terms[:, 1, 0]).max() > 1.0  # joint 2 carries gravity's stiffness


def test_coupling_columns_match_finite_differences(puma, moves) -> None:
    t = np.arange(0, moves.duration, 2e-3)
    traj = Trajectory(t, moves(t), np.zeros((t.size, 1, 3)), frame="base")
    vals = {"sync.delay": 0.003, "q2.lag": 0.006, "q2.vib_gain": 0.9,
            "q2.vib_omega": 2 * np.pi * 5.0, "q2.vib_zeta": 0.04}

    def columns(v):
        couple = {"sync.delay": v["sync.delay"], "q2.lag": v["q2.lag"]}
        cols = [c for e in ("sync_delay", "servo_lag", "residual_vibration")
                for c in effect_columns(traj, e, v, couple=couple)
                if (c.via or c.name) in vals]
        return cols, linearise(cols)

    def total(v):
        return sum(c.d for c in columns(v)[0])
    cols, (_, specs) = columns(vals)
    assert sum(c.name == "sync.delay" for c in cols) == 2  # its own column + the mode's
    assert [s.name for s in specs].count("q2.lag") == 1     # merged into one parameter
    for spec in specs:
        h = 1e-6 * abs(vals[spec.name])
        fd = (total({**vals, spec.name: vals[spec.name] + h})
              - total({**vals, spec.name: vals[spec.name] - h})) / (2 * h)
        err = np.max(np.abs(fd - spec.basis))
        assert err <= 2e-3 * np.abs(spec.basis).max(), (spec.name, err)
    # the mode is driven through the delay and the lag: without them it differs
    y_through = next(c for c in cols if c.name == "q2.vib_gain").D[:, 1]
    y_plain = joint_mode(traj, 1, vals["q2.vib_omega"], vals["q2.vib_zeta"], None)[0]
    assert np.max(np.abs(y_through - y_plain)) > 0.05 * np.abs(y_plain).max()


def test_real_robot_slow_mode_follows_the_mode_with_the_arms_terms(puma, moves) -> None:
    """The measurement behind eq. M6: a 4.3 Hz, zeta 0.03 mode on the gravity-loaded joint 2
    of the MuJoCo real robot against the constant mode and the mode with the MJCF's terms."""
    inst = Instrument(noise_sigma=1e-9)
    eff = MotionEffects(residual_vibration={2: 4.3}, vibration_damping=0.03)
    run = execute_trajectory(puma, moves, moves.duration, eff, inst, np.random.default_rng(0))
    t = run.trajectory.t
    traj = Trajectory(t, moves(t), np.zeros((t.size, 1, 3)), frame="base")
    e = run.q_actual[:, 1] - traj.q[:, 1]
    arm = build(puma, MJCFOptions(inertia="puma560")).model
    terms = mode_terms(arm, traj.q, traj.qd, traj.qdd)
    w = 2 * np.pi * 4.3
    plain = joint_mode(traj, 1, w, 0.03, None, derivatives=False)[0]
    along = joint_mode(traj, 1, w, 0.03, terms, derivatives=False)[0]
    amp = np.abs(e).max()
    rms_plain, rms_along = (float(np.sqrt(np.mean((e - y) ** 2))) for y in (plain, along))
    assert amp > 5e-3  # a large, slow mode (rad)
    assert rms_along < 2e-3 * amp   # measured 0.07 % on the benchmark's scenario 11
    assert rms_along < rms_plain / 3  # measured 7.7x better there


@pytest.mark.slow
def test_friction_and_compliance_on_the_same_joint_both_named(puma) -> None:
    """A same-joint pair the additive model handles (joint 3, 10 N m of friction on a servo of
    stiffness 1/c, c = 20 urad/(N m): play F c = 0.2 mrad); on the gravity-loaded joint 2 with
    15 N m and 30 urad/(N m) it does not (2.5x the noise; not asserted here)."""
    eff = MotionEffects(reversal_friction={3: 10.0}, dynamic_compliance={3: 2e-5})
    arm = build(puma, MJCFOptions(inertia="puma560")).model
    with tempfile.TemporaryDirectory() as tmp:
        score = _run_one(puma, MotionScenario(0, 7, eff), Path(tmp), arm, 10)
    assert score.all_found and score.joints_correct, (score.found, score.found_joints)
    assert score.ratio <= 1.5, score.ratio
