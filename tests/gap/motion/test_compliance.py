"""Dynamic compliance on a gravity-loaded joint (eq. M8: the joint's spring 1/c against its own
inertia, driven by the full inverse-dynamics torque, gravity included) named as compliance on
that joint, not as a residual vibration; and Coulomb friction with compliance on one joint
both named. Synthetic paths from independent integrators (scipy ``lsim``, a plain loop of the
play operator)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from mjcf import MJCFOptions, build, inverse_dynamics_torques
from tests.measured import tracked_tool_point
from zrp.gap.motion import Trajectory, diagnose_motion
from zrp.gap.motion.paths import exercise_moves

SIGMA = 0.02  # mm per coordinate
C, OMEGA, ZETA = 2.5e-5, 2 * np.pi * 15.0, 0.7  # rad/(N m), rad/s, 1


@pytest.fixture(scope="module")
def path(puma):
    mv = exercise_moves(np.radians([0, -20, 30, 0, 60, 0]), np.random.default_rng(1), moves=6)
    t = np.arange(0, mv.duration, 1e-3)
    q, qd, qdd = mv(t), mv(t, 1), mv(t, 2)
    arm = build(puma, MJCFOptions(inertia="puma560"))
    return t, q, inverse_dynamics_torques(arm.model, q, qd, qdd)


def _deflection(t, tau_k):
    """c omega^2 x with x'' + 2 zeta omega x' + omega^2 x = -tau_k, from static equilibrium."""
    sys_ = ([C * OMEGA**2], [1.0, 2 * ZETA * OMEGA, OMEGA**2])
    a, b, cc, d = signal.tf2ss(*sys_)
    x0 = np.linalg.solve(a, -b[:, 0] * -tau_k[0])  # at rest: a x0 + b u0 = 0
    return signal.lsim((a, b, cc, d), -tau_k, t - t[0], X0=x0)[1]


def _play(u, r):
    y = np.empty_like(u)
    y[0] = u[0]
    for i in range(1, u.size):
        y[i] = min(max(y[i - 1], u[i] - r), u[i] + r)
    return y


def test_compliance_on_a_gravity_loaded_joint_is_named_compliance(puma, path) -> None:
    t, q, tau = path
    assert np.abs(tau[:, 1]).max() > 30.0  # joint 2 carries the arm's weight
    qa = q.copy()
    qa[:, 1] += _deflection(t, tau[:, 1])
    traj = Trajectory(t, q, tracked_tool_point(puma, qa, np.random.default_rng(7)))
    d = diagnose_motion(puma, traj, torque=tau, seed=0)
    assert d.effects == ("dynamic_compliance",) and 2 in d.steps[0].joints
    est = {p.name: p for p in d.parameters}
    for name, true in (("q2.dyn_compliance", C), ("q2.dyn_omega", OMEGA),
                       ("q2.dyn_zeta", ZETA)):
        p = est[name]
        assert abs(p.value - true) < 4 * p.stderr + 0.02 * true, (name, p.value, p.stderr)
    assert d.final.rms <= 1.2 * np.sqrt(3) * SIGMA
    ranked = {c["effect"]: c["cv_rms"] for c in d.steps[0].candidates}
    vib = ranked["residual_vibration"]
    assert vib is None or vib > 1.5 * d.steps[0].cv_rms


def test_friction_and_compliance_on_one_joint_both_named(puma, path) -> None:
    t, q, tau = path
    r = 3e-4  # rad: the play of Coulomb friction against the servo
    qa = q.copy()
    qa[:, 1] = _play(q[:, 1], r) + _deflection(t, tau[:, 1])
    traj = Trajectory(t, q, tracked_tool_point(puma, qa, np.random.default_rng(8)))
    d = diagnose_motion(puma, traj, torque=tau, seed=0)
    assert set(d.effects) == {"dynamic_compliance", "reversal_friction"}
    for step in d.steps:
        assert 2 in step.joints, step
    est = {p.name: p for p in d.parameters}
    assert abs(est["q2.friction"].value - r) < 4 * est["q2.friction"].stderr + 0.02 * r
    assert abs(est["q2.dyn_compliance"].value - C) < (4 * est["q2.dyn_compliance"].stderr
                                                      + 0.02 * C)
    assert d.final.rms <= 1.2 * np.sqrt(3) * SIGMA
