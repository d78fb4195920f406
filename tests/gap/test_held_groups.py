"""Issue 34: a candidate whose joints stand in for one another is not lost to the per-group
Wald test (eqs. H1, H2 of :mod:`zrp.gap.fit.heldwald`). The well-posed solver holds the
combination the data cannot pin at its nominal value, and its covariance gives that
combination its prior's variance, which then lands on every group it spans."""

from __future__ import annotations

import warnings

import numpy as np

import zrp
from zrp.gap import diagnose
from zrp.gap.data.synthetic import Injection, synthesize
from zrp.gap.fit.heldwald import group_pvalues, wald_groups_given_held
from zrp.gap.fit.leastsq import FitResult, wald_groups
from zrp.gap.fit.wellposed import HeldDirection, solve
from zrp.gap.model.context import ParamSpec
from zrp.kinematics import uniform_joint_values

ALPHA = 1e-3


def _spec(g: str) -> ParamSpec:
    return ParamSpec(f"q{g}.w", "rad/mm", "joint_compliance", "dq", int(g), 0,
                     np.zeros((1, 7)), group=f"q{g}")


def _linear_fit(cols: np.ndarray, y: np.ndarray, groups: list[str]) -> FitResult:
    """The well-posed solver on r(theta) = cols theta - y (scales 1), one group each."""
    specs = tuple(_spec(g) for g in groups)
    p = len(specs)
    sol = solve(lambda t: (cols @ t - y, cols), lambda t: cols @ t - y, np.zeros(p),
                np.zeros(p), np.ones(p), [s.name for s in specs])
    return FitResult(specs, sol.theta, sol.cov, sol.residual, sol.jac, np.eye(3),
                     np.arange(y.size // 3), sol.converged, sol.held, held_cov=sol.held_cov)


def _collinear(seed: int = 0, eps: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
    """Joint 2's column, joint 4's nearly the same, joint 5's unrelated; the signal is
    joint 2's, 25 noise sigmas per coordinate."""
    rng = np.random.default_rng(seed)
    m = 600
    x = rng.normal(size=m)
    cols = np.column_stack([x, x + eps * rng.normal(size=m), rng.normal(size=m)])
    return cols, 0.05 * x + 0.01 * rng.normal(size=m)


def test_a_collinear_pair_that_the_plain_wald_test_loses_is_kept():
    f1 = _linear_fit(*_collinear(), ["2", "4", "5"])
    assert len(f1.held) == 1  # the difference of joints 2 and 4 is held at nominal
    held = set(f1.held[0].parameters)
    assert held == {"q2.w", "q4.w"}
    thr = ALPHA / 3
    plain = wald_groups(f1, 0)
    assert all(p > thr for p in plain.values())  # the old test: "no joint significant"
    pv = group_pvalues(f1, 0, ALPHA)
    assert pv["joint_compliance:q2"] < 1e-50 and pv["joint_compliance:q4"] < 1e-50
    # joint 5: no held combination spans it, the plain test decides, and it is not needed
    assert pv["joint_compliance:q5"] == plain["joint_compliance:q5"] > thr
    # the estimated part of the covariance is that of the kept direction only
    c_est = f1.cov - f1.held_cov
    assert np.linalg.eigvalsh(c_est).min() > -1e-12 * np.abs(c_est).max()
    assert np.linalg.matrix_rank(f1.held_cov, tol=1e-9) == 1


def test_without_held_combinations_the_plain_wald_test():
    rng = np.random.default_rng(1)
    cols = rng.normal(size=(600, 2))
    y = 0.05 * cols[:, 0] + 0.01 * rng.normal(size=600)
    f1 = _linear_fit(cols, y, ["2", "5"])
    assert not f1.held and np.all(f1.held_cov == 0.0)
    assert group_pvalues(f1, 0, ALPHA) == wald_groups(f1, 0) == wald_groups_given_held(f1, 0)
    assert group_pvalues(f1, 0, ALPHA)["joint_compliance:q2"] < 1e-50


def _by_hand(theta: list[float], est_var: list[float], held_weights: list[float]
             ) -> FitResult:
    """A fit of three one-parameter groups whose estimated parts are independent with
    variances ``est_var`` and one held combination (unit prior) with ``held_weights``."""
    v = np.array(held_weights, dtype=float)
    v /= np.linalg.norm(v)
    held_cov = np.outer(v, v)
    cov = np.diag(est_var) + held_cov
    names = [f"q{g}.w" for g in "234"]
    order = [j for j in np.argsort(-np.abs(v)) if abs(v[j]) >= 0.1]
    held = (HeldDirection(tuple(names[j] for j in order), tuple(float(v[j]) for j in order),
                          0.01, 0.02, False),)
    p = len(theta)
    return FitResult(tuple(_spec(g) for g in "234"), np.array(theta, dtype=float), cov,
                     np.zeros(30), np.zeros((30, p)), np.eye(3), np.arange(10), True, held,
                     held_cov=held_cov)


def test_a_held_combination_that_spans_a_group_not_needed_stays_with_the_plain_test():
    """Joints 2 and 3 share a held combination; joint 3's estimated part is nothing: keeping
    joint 2 alone would release the combination (once joint 3 is dropped it becomes
    estimable), keeping joint 3 would add what the data do not need: the plain test decides
    (here: neither is kept)."""
    f = _by_hand([0.05, 1e-4, 0.0], [1e-6, 1e-6, 1e-6], [1.0, 1.0, 0.0])
    given = wald_groups_given_held(f, 0)
    assert given["joint_compliance:q2"] < 1e-50 and given["joint_compliance:q3"] > 0.5
    pv = group_pvalues(f, 0, ALPHA)
    assert pv == wald_groups(f, 0)
    assert pv["joint_compliance:q2"] > ALPHA / 3  # the prior's variance hides it
    # the same with joint 3 needed too: both kept by (H1)
    f = _by_hand([0.05, 0.05, 0.0], [1e-6, 1e-6, 1e-6], [1.0, 1.0, 0.0])
    pv = group_pvalues(f, 0, ALPHA)
    assert pv["joint_compliance:q2"] < 1e-50 and pv["joint_compliance:q3"] < 1e-50
    assert pv["joint_compliance:q4"] == wald_groups(f, 0)["joint_compliance:q4"]


def test_a_body_error_lost_to_its_collinear_neighbour_is_found():
    """A PUMA whose joint 3 moves by 1 mrad only, with an error on body 4 (after joint 3):
    bodies 3 and 4 then stand in for one another, the fit holds their difference, and the
    plain Wald test refused both, so the search (0.5.0) fitted joint offsets, axis tilts and
    backlash in their place. With eq. H2 the body error is the first step, clearly best on
    cross-validation, and the backward pass keeps one of the collinear pair."""
    puma = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    limits = np.array([[-2.0, 2.0]] * 6)
    limits[2] = [0.5, 0.501]
    q = uniform_joint_values(puma, 60, rng, limits)
    meas = synthesize(puma, q, Injection(link={4: (0.3, -0.2, 0.1)}), rng=rng,
                      noise_sigma=0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(puma, meas, seed=0)
    first = d.steps[0]
    assert first.effect == "link_length" and 4 in first.joints
    others = [c.cv_rms for c in first.candidates if c.effect != "link_length"
              and c.cv_rms == c.cv_rms]
    assert first.cv_rms < 0.5 * min(others)
    assert [s.effect for s in d.steps] == ["link_length"]
    assert set(d.final_joints) == {"link_length"}
    assert d.final.rms <= 1.2 * d.noise_floor.rms
