"""The inertial regressor against MuJoCo's own inverse dynamics, and the payload block against
a point mass added to the model."""

from __future__ import annotations

import copy

import numpy as np

from mjcf import inverse as inr
from sim.studies.dynamics.truth import HiddenDynamics, true_model
from zrp.gap.dynamics import inertia as pure
from zrp.gap.dynamics.effects import payload_columns


def _states(n, s=40, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(-2, 2, (s, n)), rng.normal(0, 1, (s, n)), rng.normal(0, 3, (s, n))


def test_regressor_reproduces_mj_inverse(ur5e):
    q, qd, qdd = _states(ur5e.n)
    m = ur5e.model
    y, labels = ur5e.regressor(q, qd, qdd)
    phi = np.concatenate([inr.body_params(m, b) for b in ur5e.moving_bodies()])
    tau = inr.inverse_dynamics(m, q, qd, qdd)
    rest = m.dof_armature * qdd + m.dof_damping * qd
    assert len(labels) == y.shape[-1] == 10 * len(ur5e.moving_bodies())
    np.testing.assert_allclose(y @ phi + rest, tau, atol=1e-9 * np.abs(tau).max())


def test_body_params_round_trip(ur5e):
    m = copy.deepcopy(ur5e.model)
    for b in ur5e.moving_bodies():
        phi = inr.body_params(m, b)
        assert pure.pseudo_inertia_ok(phi)
        inr.set_body_params(m, b, phi)
        np.testing.assert_allclose(inr.body_params(m, b), phi, atol=1e-12)
    bad = inr.body_params(m, 3).copy()
    bad[0] = -1.0
    assert not pure.pseudo_inertia_ok(bad)


def test_base_directions_rank_below_parameters(ur5e):
    v, _ = pure.base_directions(ur5e)
    p = 10 * len(ur5e.moving_bodies())
    assert v.shape[0] == p and 20 < v.shape[1] < p
    np.testing.assert_allclose(v.T @ v, np.eye(v.shape[1]), atol=1e-10)


def test_payload_columns_match_a_point_mass(ur5e):
    q, qd, qdd = _states(ur5e.n, seed=5)
    cols = payload_columns(ur5e, q, qd, qdd)
    tau0 = inr.inverse_dynamics(ur5e.model, q, qd, qdd)
    heavy = true_model(ur5e, HiddenDynamics(payload_kg=2.0))
    exact = inr.inverse_dynamics(heavy, q, qd, qdd) - tau0
    np.testing.assert_allclose(cols[..., 0] * 2.0, exact, atol=1e-9 * np.abs(exact).max())
    # an offset d: first order in d (the columns m d); the second-order term m |d|^2 is left
    d = np.array([0.01, -0.02, 0.015])
    off = true_model(ur5e, HiddenDynamics(payload_kg=2.0, payload_offset_m=d))
    exact = inr.inverse_dynamics(off, q, qd, qdd) - tau0
    lin = cols @ np.array([2.0, *(2.0 * d)])
    assert np.abs(lin - exact).max() < 0.02 * np.abs(exact).max()
