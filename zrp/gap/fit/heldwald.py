"""Which significance groups the data need, given the combinations the fit holds.

The well-posed solver (:mod:`zrp.gap.fit.wellposed`) holds at their nominal values the
parameter combinations the data cannot pin, and its covariance gives them their prior's
variance (the second term of eq. W3). A per-group Wald test on that covariance
(:func:`zrp.gap.fit.leastsq.wald_groups`) fails for every group a held combination spans,
however clearly the data see the rest of the group: of two near-collinear joints (a compliance
at joint 2 and one at joint 4 that the poses can barely tell apart, three axes tilted
together) each looks insignificant alone, and the whole candidate was refused ("no joint
significant") although its cross-validated error was the best by far (issue 34).

The fit does not estimate the held combinations: it keeps them at their nominal values. The
test here is the Wald test of each group given that, on the covariance of what the fit does
estimate (the first term of eq. W3),

    C_est = C - C_held,   chi2_g = theta_g^T C_est,gg^+ theta_g,   df = rank C_est,gg   (H1)

(the pseudo-inverse in the group's own scale, its rank at :data:`RANK_RTOL` of the group's
full variances: a direction of the group that only held combinations reach has no estimate
to test). With nothing held C_est = C and (H1) is the plain Wald test.

Nothing the data cannot pin may be released by what is dropped afterwards: a held combination
becomes estimable once one of its members is dropped, and the fit then picks one of the many
ways to explain the same positions (tests/gap/test_orientation_search.py: the tilts of three
parallel axes held together with two other axes' - nearly a rotation of the whole arm - must
stay at nominal from positions alone). Keeping a member the data do not need would add a
parameter they do not need. So (H1) replaces the plain test only for the groups of held
combinations whose members all pass it (they stay in the model together, the combination
still held; :func:`group_pvalues`):

    p_g = p_g(H1)    if p_h(H1) < alpha / G for every group h of every held
                     combination that spans g                                          (H2)
          p_g(Wald)  otherwise (no held combination spans g, or one spans a group that
                     (H1) does not need)

(G: the number of groups tested; the members of a held combination: the parameters its
reported direction names, weight at least 0.1 in tolerance units, at most six,
:class:`zrp.gap.fit.wellposed.HeldDirection`).

The search (:func:`zrp.gap.search.greedy.greedy_search`) tests a candidate's groups by (H2);
its backward pass keeps the plain test, so of a near-collinear pair that entered together one
is dropped there and the refit estimates the other (tests/gap/test_backward_pass.py).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import special

from zrp.gap.fit.leastsq import FitResult, group_key, wald_groups
from zrp.gap.fit.wellposed import rank_chi2
from zrp.gap.model.context import ParamSpec

__all__ = ["RANK_RTOL", "group_pvalues", "wald_groups_given_held"]

#: eigenvalues of a group's estimated covariance (in the scale of its full variances) below
#: this are directions only held combinations reach (not tested).
RANK_RTOL = 1e-10


def _chi2(theta: np.ndarray, c_est: np.ndarray, c_full: np.ndarray) -> tuple[float, int]:
    """chi2 and df of (H1) for one group."""
    return rank_chi2(theta, c_est, c_full, RANK_RTOL)


def wald_groups_given_held(result: FitResult, first: int,
                           tested: Callable[[ParamSpec], bool] | None = None
                           ) -> dict[str, float]:
    """p-value of (H1) per :func:`~zrp.gap.fit.leastsq.group_key` for the parameters from
    index ``first`` on (``tested``: as in :func:`~zrp.gap.fit.leastsq.wald_groups`); 1 for a
    group with no estimated direction. Without held combinations (or their share of the
    covariance unknown), the plain Wald test."""
    if not result.held or result.held_cov is None:
        return wald_groups(result, first, tested)
    c_est = result.cov - result.held_cov
    groups: dict[str, list[int]] = {}
    for i in range(first, len(result.specs)):
        if tested is None or tested(result.specs[i]):
            groups.setdefault(group_key(result.specs[i]), []).append(i)
    out: dict[str, float] = {}
    for g, idx in groups.items():
        ix = np.ix_(idx, idx)
        if not (np.all(np.isfinite(c_est[ix])) and np.all(np.isfinite(result.theta[idx]))):
            out[g] = 1.0
            continue
        chi2, df = _chi2(result.theta[idx], c_est[ix], result.cov[ix])
        out[g] = float(special.chdtrc(df, chi2)) if df else 1.0
    return out



def _members(result: FitResult, first: int) -> list[set[str]]:
    """The groups (of the parameters from index ``first`` on) each held combination spans."""
    group_of = {s.name: group_key(s) for s in result.specs[first:]}
    return [{group_of[n] for n in h.parameters if n in group_of} for h in result.held]


def group_pvalues(result: FitResult, first: int, alpha: float) -> dict[str, float]:
    """p-value per group (the parameters from index ``first`` on) by eq. H2: the test given
    the held combinations (H1) for the groups of held combinations whose members all pass it
    at ``alpha`` / groups, the plain Wald test for the others."""
    plain = wald_groups(result, first)
    if not result.held or result.held_cov is None:
        return plain
    given = wald_groups_given_held(result, first)
    thr = alpha / max(len(given), 1)
    passes = {g for g, p in given.items() if p < thr}
    spans = [m for m in _members(result, first) if m]
    out = dict(plain)
    for g in given:
        mine = [m for m in spans if g in m]
        if mine and all(m <= passes for m in mine):
            out[g] = given[g]
    return out
