"""Lumped compliance weights held at sum 0 (issue 34, :mod:`zrp.gap.fit.sumzero`): data whose
free fit wants joint 2's weights to sum below 0 (a joint deflecting against its load, injected)
give weights on the bound of their domain, sum 0, the others free: a lower residual than
taking them all out (the stricter model of issue 33), and the Kuhn-Tucker conditions of least
squares subject to sum >= 0 met (the gradient J^T r is a non-negative multiple of the
constraint's normal; the exact constrained optimum, independent of the solver)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import zrp
from zrp.gap import diagnose
from zrp.gap.data.synthetic import Injection, synthesize
from zrp.gap.fit.constrained import outside_domains, within_domains
from zrp.gap.fit.fullpose import fit_full_pose
from zrp.gap.fit.leastsq import fit, initial_registration, wald_groups
from zrp.gap.fit.wellposed import rank_chi2
from zrp.gap.model.context import Context
from zrp.gap.model.domains import SUM_RTOL, sum_inside
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.report.verdict import identification_text
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")


def _setup():
    rng = np.random.default_rng(7)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 150, rng),
                      Injection(compliance={2: -4e-5}, masses={"ee": 5.0}), rng=rng,
                      noise_sigma=0.01)
    ctx = Context(PUMA, meas)
    poses = np.arange(len(meas.pose_ids))
    reg = registration_parameters(ctx)
    theta0, rb0 = initial_registration(ctx, reg, poses)
    specs = [s for s in effect_parameters(ctx, "joint_compliance")[0]
             if s.name.startswith("q2.w_")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        free = fit(ctx, reg + specs, poses, np.concatenate([theta0, np.zeros(len(specs))]),
                   rb0)
    return ctx, poses, reg, specs, free, theta0, rb0


def test_weights_held_at_sum_zero_fit_better_than_taken_out():
    ctx, poses, reg, specs, free, theta0, rb0 = _setup()
    w = slice(len(reg), None)
    assert len(specs) >= 2 and math.fsum(free.theta[w]) < -1e-6  # the premise
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        held, reasons = within_domains(ctx, free, len(reg), poses, rb0)
        out = fit(ctx, reg, poses, theta0, rb0)  # the take-out: every q2 weight at 0
    vals = held.theta[w]
    assert [s.name for s in held.specs] == [s.name for s in free.specs]
    assert sum_inside(vals) and abs(math.fsum(vals)) <= SUM_RTOL * math.fsum(np.abs(vals))
    assert np.max(np.abs(vals)) > 1e-7  # not all 0
    assert outside_domains(ctx, held) == []
    assert any(r.startswith("q2 lumped weights held at sum 0") for r in reasons)
    assert free.rss < held.rss < out.rss
    # Kuhn-Tucker: grad (rss / 2) = J^T r = mu a, mu >= 0, a the sum's normal (1 on the
    # weights): equal on the weights, ~0 on the registration
    g = held.jac.T @ held.residual
    scale = np.linalg.norm(held.jac, axis=0)
    gs = g / scale
    mu = gs[w] * scale[w]  # J^T r on the weights themselves (the normal is 1 there)
    assert np.all(mu > 0) and np.ptp(mu) <= 1e-3 * np.max(mu)
    assert np.max(np.abs(gs[: len(reg)])) <= 1e-3 * np.max(np.abs(gs[w]))
    # the covariance: of rank f, the sum's variance 0, the statistics count f parameters
    a = np.zeros(len(held.specs))
    a[w] = 1.0
    assert held.n_free == len(held.specs) - 1 and held.dof == held.n_res - held.n_free
    assert a @ held.cov @ a <= 1e-9 * np.max(np.diag(held.cov)[w])
    assert np.all(np.diag(held.cov)[w] > 0)
    # the Wald test of the joint's weights on that singular covariance: its rank, 2 of 3
    assert rank_chi2(held.theta[w], held.cov[w, w], held.cov[w, w])[1] == len(specs) - 1
    assert wald_groups(held, len(reg))["joint_compliance:q2"] < 1e-12


def test_full_pose_fit_holds_the_sum_too():
    """The full-pose fit's own domain loop (here its position-only variant) holds the weights
    at sum 0 as the position fits do: the same values, the eliminated weight's standard error
    from the others' covariance."""
    ctx, poses, reg, specs, free, _, rb0 = _setup()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        held, _ = within_domains(ctx, free, len(reg), poses, rb0)
        fp = fit_full_pose(ctx, reg + specs, poses, orientation=False)
    w = slice(len(reg), None)
    assert [s.name for s in fp.specs] == [s.name for s in held.specs]
    assert sum_inside(fp.theta[w]) and abs(math.fsum(fp.theta[w])) <= SUM_RTOL * math.fsum(
        np.abs(fp.theta[w]))
    np.testing.assert_allclose(fp.theta[w], held.theta[w], rtol=1e-6)
    assert any("q2 lumped weights held at sum 0" in r for r in fp.outside_domain)
    others = fp.cov[w, w][:-1, :-1]
    assert fp.stderr[-1] == pytest.approx(math.sqrt(others.sum()), rel=1e-9)
    assert fp.position.tied is not None and fp.position.n_free == len(fp.specs) - 1


def test_the_diagnosis_says_the_weights_are_held_not_taken_out():
    """The search holds them (not "taken out") and says so in the verdict and in the record a
    calibration takes (``taken_out_non_physical``)."""
    rng = np.random.default_rng(7)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 150, rng),
                      Injection(compliance={2: -4e-5}, masses={"ee": 5.0}), rng=rng,
                      noise_sigma=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(PUMA, meas, seed=0, effects=("joint_compliance",))
    w = [p for p in d.final_fit.specs if p.name.startswith("q2.w_")]
    assert len(w) >= 2  # kept, held at sum 0
    assert sum_inside([d.final_fit.value(p.name) for p in w])
    said = [t for t in identification_text(d) if "q2 lumped weights held at sum 0" in t]
    assert said and all("taken out (" not in t for t in said)
    assert any("q2 lumped weights held at sum 0" in t for t in d.calibration_record.taken_out)
