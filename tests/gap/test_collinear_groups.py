"""Issue 34: a candidate whose joints stand in for one another (near-collinear groups) is not
lost to the per-group Wald test. The well-posed solver holds the combination the data cannot
pin at its prior (eq. W3), whose variance then lands on both groups, so each looks
insignificant alone; backward elimination on the identifiable parts
(:mod:`zrp.gap.search.groups`) keeps one of them."""

from __future__ import annotations

import numpy as np

from zrp.gap.fit.leastsq import FitResult, wald_groups
from zrp.gap.fit.wellposed import solve
from zrp.gap.model.context import ParamSpec
from zrp.gap.search.groups import identifiable_groups, identifiable_pvalues


def _linear_fit(cols: np.ndarray, y: np.ndarray, groups: list[str],
                scale: float) -> FitResult:
    """The well-posed solver on r(theta) = cols theta - y, each parameter its own group."""
    specs = tuple(ParamSpec(f"q{g}.w", "rad/mm", "joint_compliance", "dq", int(g), 0,
                            np.zeros((1, 7)), group=f"q{g}") for g in groups)
    p = len(specs)
    sol = solve(lambda t: (cols @ t - y, cols), lambda t: cols @ t - y, np.zeros(p),
                np.zeros(p), np.full(p, scale), [s.name for s in specs])
    return FitResult(specs, sol.theta, sol.cov, sol.residual, sol.jac, np.eye(3),
                     np.arange(y.size // 3), sol.converged, sol.held)


def _collinear_case(seed: int = 0, eps: float = 1e-5):
    rng = np.random.default_rng(seed)
    m = 600
    x = rng.normal(size=m)
    partner = x + eps * rng.normal(size=m)  # another joint's column, nearly the same
    other = rng.normal(size=m)  # a third joint that explains nothing
    y = 0.05 * x + 0.01 * rng.normal(size=m)  # the signal: 25 noise sigmas per coordinate
    return np.column_stack([x, partner, other]), y


def test_wald_groups_miss_a_collinear_pair_that_backward_elimination_keeps():
    cols, y = _collinear_case()
    f1 = _linear_fit(cols, y, ["2", "4", "5"], scale=1.0)
    assert f1.held  # the difference of the two collinear columns is held at the prior
    wald = wald_groups(f1, 0)
    thr = 1e-3 / 3
    assert all(p > thr for p in wald.values())  # the old test: "no joint significant"
    kept, pv = identifiable_groups(f1, 0, 1e-3)
    assert len(kept) == 1 and kept <= {"joint_compliance:q2", "joint_compliance:q4"}
    assert pv[next(iter(kept))] < 1e-50
    # against each other, neither collinear group has an identifiable part of its own
    both = identifiable_pvalues(f1, 0, ["joint_compliance:q2", "joint_compliance:q4"])
    assert both == {"joint_compliance:q2": 1.0, "joint_compliance:q4": 1.0}


def test_independent_groups_are_tested_as_usual():
    """Without collinearity the identifiable-part test agrees with the Wald test: the joint
    with the signal is kept, the one without is dropped."""
    rng = np.random.default_rng(1)
    cols = rng.normal(size=(600, 2))
    y = 0.05 * cols[:, 0] + 0.01 * rng.normal(size=600)
    f1 = _linear_fit(cols, y, ["2", "5"], scale=1.0)
    assert not f1.held
    kept, _ = identifiable_groups(f1, 0, 1e-3)
    wald = wald_groups(f1, 0)
    assert kept == {"joint_compliance:q2"} == {g for g, p in wald.items() if p < 1e-3 / 2}
