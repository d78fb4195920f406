"""The physically consistent link inertia fit (zrp.gap.dynamics.physical, eq. P1-P5): physical by
construction, equal to the unconstrained fit when that is already physical, the right torques
on a known link change, and, where the minimum-norm set is not physical, no worse on withheld
data than the post-hoc repair it replaced (tests/sim/dynamics/_posthoc.py)."""

from __future__ import annotations

import numpy as np
import pytest

from mjcf.inverse import body_params, inverse_dynamics
from sim.studies.dynamics.arms import BENCH_ARMS
from sim.studies.dynamics.scenarios import scenario_command
from tests.gap.dynamics._posthoc import feasible_inertias
from zrp.gap.dynamics.effects import candidate_effects, inertial_correction
from zrp.gap.dynamics.fit import design, folds, solve
from zrp.gap.dynamics.inertia import pseudo_inertia_min
from zrp.gap.dynamics.physical import physical_cross_validate, physical_fit


@pytest.fixture(scope="module")
def puma_states():
    bench = BENCH_ARMS["puma"]
    arm = bench.load()
    t = np.arange(0.0, 8.0, 0.01)
    q, qd, qdd = scenario_command(bench.q0_array, bench.amplitude_rad, 3).evaluate(t)
    tau0 = inverse_dynamics(arm.model, q, qd, qdd)
    inertial = [e for e in candidate_effects(arm, q, qd, qdd, tau0) if e.name == "inertial"]
    return arm, (q, qd, qdd), inertial


def _link_torques(arm, states, dphi):
    """The torques of a change dphi of every link's parameters, from MuJoCo's regressor."""
    y, _ = arm.regressor(*states)
    return y @ dphi


def _phi0(arm):
    return np.concatenate([body_params(arm.model, b) for b in arm.moving_bodies()])


def _physical(phi):
    """Positive semi-definite pseudo-inertia to rounding (the PUMA's own first and third
    links are flat: on the boundary)."""
    return pseudo_inertia_min(phi) >= -1e-12 * np.abs(phi).max()


def test_physical_link_change_is_matched_with_its_torques(puma_states):
    arm, states, inertial = puma_states
    phi0 = _phi0(arm)
    dphi = np.zeros_like(phi0)
    dphi[10:20] = 0.25 * phi0[10:20]  # link 2 a quarter heavier, same shape: physical
    sigma = np.full(arm.n, 0.05)
    rng = np.random.default_rng(0)
    b = _link_torques(arm, states, dphi) + rng.normal(0.0, 1.0, (len(states[0]), arm.n)) * sigma
    fit = physical_fit(arm, inertial, b, sigma)
    assert all(_physical(p) for p in fit.phi.values())
    # noise makes the small wrist links non-physical unconstrained; the physical set is
    # within what the noise explains, and its torques differ from the unconstrained ones
    # by a fraction of the noise
    assert fit.matched and "to within the noise" in fit.describe()
    assert fit.torque_gap < 0.2
    got = np.concatenate([fit.phi[bb] for bb in arm.moving_bodies()]) - phi0
    # the torques of the change (on other states: the link's visible combinations) are right
    rng = np.random.default_rng(1)
    other = (rng.uniform(-2, 2, (50, arm.n)), rng.normal(0, 1, (50, arm.n)),
             rng.normal(0, 3, (50, arm.n)))
    err = _link_torques(arm, other, got - dphi)
    assert np.sqrt(np.mean(err**2)) < 0.1 * np.sqrt(np.mean(_link_torques(arm, other, dphi)**2))


def test_non_physical_torques_give_a_physical_set_that_says_how_far(puma_states):
    arm, states, inertial = puma_states
    phi0 = _phi0(arm)
    dphi = np.zeros_like(phi0)
    dphi[20:] = -1.5 * phi0[20:]  # links 3.. with negative masses: no physical set does this
    sigma = np.full(arm.n, 0.05)
    rng = np.random.default_rng(2)
    b = _link_torques(arm, states, dphi) + rng.normal(0.0, 1.0, (len(states[0]), arm.n)) * sigma
    fit = physical_fit(arm, inertial, b, sigma)
    assert not fit.unconstrained_physical and not fit.matched
    assert fit.distance_se > 3 * fit.noise_se and fit.torque_gap > 1.0
    assert all(_physical(p) for p in fit.phi.values())
    assert "cannot match" in fit.describe() and "standard errors" in fit.describe()
    # the torques it explains: at least as many as the post-hoc repair's (full-row chi^2,
    # computed here from MuJoCo's regressor, not from the fit's reduced problem)
    unc = solve(design(inertial, *b.shape), b, sigma, with_cov=False)
    ok, shrink, repaired = feasible_inertias(arm, unc.theta, inertial[0].basis)
    assert not ok and shrink < 1.0
    chi2 = {}
    for name, phis in (("physical", fit.phi), ("repaired", repaired)):
        d = np.concatenate([phis[bb] for bb in arm.moving_bodies()]) - phi0
        chi2[name] = float(np.sum(((b - _link_torques(arm, states, d)) / sigma) ** 2))
    assert chi2["physical"] <= chi2["repaired"]


@pytest.fixture(scope="module")
def ur5e_inertial_case(ur5e):
    """The UR5e benchmark case "inertial", seed 1: the minimum-norm link inertias are not
    physical and the post-hoc repair shrank the correction to about a quarter."""
    from sim.studies.dynamics.scenarios import draw_hidden
    from sim.studies.dynamics.truth import simulate
    from zrp.gap.dynamics import diagnosis as dg
    from zrp.gap.dynamics.select import forward_select

    bench = BENCH_ARMS["ur5e"]
    command = scenario_command(bench.q0_array, bench.amplitude_rad, 1)
    hidden, sigma_true, _ = draw_hidden(ur5e, command, "inertial", 1)
    log = simulate(ur5e, hidden, command, 20.0, noise_nm=sigma_true, seed=1)
    opt = dg.DynamicsOptions(window_s=0.1)
    sigma = dg.torque_noise(log, opt.window_s)
    s, _ = dg._decimated(log, opt)
    tau0 = inverse_dynamics(ur5e.model, s.q, s.qd, s.qdd)
    b, b_raw = s.tau - tau0, s.tau_raw - tau0
    guard = max(1, round(0.5 * opt.window_s * opt.fit_rate_hz))
    # the link inertias alone (the diagnosis would name the one link's mass first)
    links = [e for e in candidate_effects(ur5e, s.q, s.qd, s.qdd, tau0)
             if e.name not in ("link_mass", "absent_part", "payload")]
    chosen, _, _ = forward_select(links, b, b_raw, sigma, folds=opt.folds, guard=guard,
                                  min_rel=opt.min_rel, min_abs=opt.min_abs,
                                  max_effects=8)
    return log, sigma_true, sigma, b, b_raw, chosen, guard, opt.folds


def _posthoc_withheld(arm, chosen, b, sigma, k, guard):
    """Out-of-segment torques of the replaced method: the unconstrained fit, its links
    repaired (null space, else shrunk), the other effects as fitted."""
    d = design(chosen, *b.shape)
    i = next(j for j, e in enumerate(chosen) if e.name == "inertial")
    sl, ein = d.slices[i], chosen[i]
    other = np.setdiff1d(np.arange(d.a.shape[-1]), np.arange(sl.start, sl.stop))
    phi0 = _phi0(arm)
    pred, shrinks = np.zeros_like(b), []
    for seg in folds(b.shape[0], k):
        keep = np.ones(b.shape[0], dtype=bool)
        keep[max(seg[0] - guard, 0):seg[-1] + guard + 1] = False
        fit = solve(d, b, sigma, np.flatnonzero(keep), with_cov=False)
        _, shrink, phis = feasible_inertias(arm, fit.theta[sl], ein.basis)
        dphi = np.concatenate([phis[bb] for bb in arm.moving_bodies()]) - phi0
        pred[seg] = d.a[seg][..., other] @ fit.theta[other] + ein.full[seg] @ dphi
        shrinks.append(shrink)
    return pred, shrinks


@pytest.mark.slow
def test_ur5e_case_physical_and_no_worse_than_the_shrunk_repair(ur5e, ur5e_inertial_case):
    _, sigma_true, sigma, b, b_raw, chosen, guard, k = ur5e_inertial_case
    assert [e.name for e in chosen] == ["inertial"]
    e = chosen[0]
    unc = solve(design(chosen, *b.shape), b, sigma, with_cov=False)
    minimum_norm = inertial_correction(ur5e, unc.theta, e.basis)
    assert min(pseudo_inertia_min(p) for p in minimum_norm.values()) < 0.0  # not physical
    old, shrinks = _posthoc_withheld(ur5e, chosen, b, sigma, k, guard)
    assert max(shrinks) < 0.5  # the repair shrank the correction in every segment
    new, fits = physical_cross_validate(ur5e, chosen, b, sigma, k, guard)
    assert all(pseudo_inertia_min(p) > 0.0 for f in fits for p in f.phi.values())
    rms_old = np.sqrt(np.mean((b_raw - old) ** 2, axis=0)) / sigma_true
    rms_new = np.sqrt(np.mean((b_raw - new) ** 2, axis=0)) / sigma_true
    print(f"withheld RMS / noise, worst joint: physical {rms_new.max():.3f}, "
          f"post-hoc repair {rms_old.max():.3f} (shrunk to {min(shrinks):.0%}.."
          f"{max(shrinks):.0%})")
    assert rms_new.max() <= rms_old.max() and np.all(rms_new <= rms_old + 0.01)
    assert rms_new.max() <= 1.5


@pytest.mark.slow
def test_ur5e_case_diagnosis_says_how_far(ur5e, ur5e_inertial_case):
    from zrp.gap.dynamics.diagnosis import EFFECT_NAMES, DynamicsOptions, diagnose_dynamics
    from zrp.gap.dynamics.report import diagnosis_json

    log, sigma_true = ur5e_inertial_case[:2]
    links_only = tuple(n for n in EFFECT_NAMES if n not in ("link_mass", "absent_part"))
    diag = diagnose_dynamics(ur5e, log, DynamicsOptions(effects=links_only))
    f = diag.inertial_fit
    assert f is not None and not f.unconstrained_physical
    assert all(pseudo_inertia_min(p) > 0.0 for p in diag.inertial_phi.values())
    assert any(f.describe() == n for n in diag.notes)
    assert ("cannot match" in f.describe()) == (f.distance_se > f.noise_se)
    assert np.all(diag.rms_after <= 1.5 * sigma_true)
    assert diagnosis_json(diag)["inertial_fit"]["distance_se"] == pytest.approx(f.distance_se)
