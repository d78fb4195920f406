"""Which joints of a candidate effect the data need: backward elimination of its significance
groups, each tested on its identifiable part.

The per-group Wald test of a fit (:func:`zrp.gap.fit.leastsq.wald_groups`) uses the fit's
covariance, in which a combination the data cannot pin carries the prior's variance (its
manufacturing tolerance, eq. W3 of :mod:`zrp.gap.fit.wellposed`). When two groups are
near-collinear (a joint's compliance weights and another joint's, a lumped mass point and
the payload column: the ``q5.w_load ~ nothing`` kind of warning), that prior variance lands
on both, so each group alone looks insignificant although together they explain most of the
residual: the whole candidate was refused ("no joint significant") although its
cross-validated error was the best by far (issue 34: a 7-axis arm at three payloads).

Here the fit is linearised at its solution, r(theta) ~ y + J theta with y = r1 - J theta1
(the residual with every fitted parameter at zero; the columns of J normalised), and a group
g among the candidate's
remaining groups S is tested on what only it can explain: its columns projected off the
span of the current model's and the other remaining groups' columns, keeping the directions
whose projection retains at least :data:`IDENTIFIABLE_FRACTION` of the columns' norm (the
collinear part is dropped). The statistic is the residual sum of squares those directions
remove, over sigma^2 (the candidate fit's residual variance per coordinate),

    chi2_g = |U_g^T y|^2 / sigma^2,  df = rank of the identifiable part            (G1)

Backward elimination: the least significant group goes and the others are retested against
the rest until every remaining group passes at alpha / (number of groups of the candidate),
so of two groups that stand in for each other one is kept.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from zrp.arrays import F64
from zrp.gap.fit.leastsq import FitResult, group_key

__all__ = ["IDENTIFIABLE_FRACTION", "identifiable_groups", "identifiable_pvalues"]

#: directions of a group whose projection off the other columns keeps less than this fraction
#: of their norm are collinear with them and not tested.
IDENTIFIABLE_FRACTION = 1e-3


def _pvalue(A: F64, b: F64, g: list[int], o: list[int], s2: float) -> float:
    """p-value of eq. G1 for the columns ``g`` against the columns ``o``, from the Gram
    matrix ``A`` of the normalised Jacobian and ``b`` = its transpose times y: the projected
    columns' Gram matrix is the Schur complement S = A_gg - A_go A_oo^+ A_og and their
    products with y are c = b_g - A_go A_oo^+ b_o, so chi2 = sum_i (v_i^T c)^2 / w_i over the
    eigenpairs of S with sqrt(w_i) > :data:`IDENTIFIABLE_FRACTION`."""
    if s2 <= 0 or not g:
        return 1.0
    agg, bg = A[np.ix_(g, g)], b[g]
    if o:
        ago = A[np.ix_(g, o)]
        x = np.linalg.pinv(A[np.ix_(o, o)], rcond=1e-12, hermitian=True) @ np.column_stack(
            [ago.T, b[o]])
        agg = agg - ago @ x[:, :-1]
        bg = bg - ago @ x[:, -1]
    w, v = np.linalg.eigh(agg)
    ok = w > IDENTIFIABLE_FRACTION ** 2
    if not np.any(ok):
        return 1.0
    chi2 = float(np.sum((v[:, ok].T @ bg) ** 2 / w[ok])) / s2
    return float(special.chdtrc(int(ok.sum()), chi2))


def _gram(f1: FitResult) -> tuple[F64, F64]:
    """Gram matrix of the normalised Jacobian of ``f1`` and its products with
    y = r1 - J theta1 (the residual with every fitted parameter at zero)."""
    J = f1.jac
    d = np.linalg.norm(J, axis=0)
    d = np.where(d > 0, d, 1.0)
    y = f1.residual - J @ f1.theta
    Jn = J / d
    return Jn.T @ Jn, Jn.T @ y


def identifiable_pvalues(f1: FitResult, nb: int, groups: list[str],
                         gram: tuple[F64, F64] | None = None) -> dict[str, float]:
    """p-value of eq. G1 per group in ``groups`` (the candidate's parameters of ``f1`` from
    index ``nb`` on; the first ``nb`` are the current model), each against the others."""
    A, b = _gram(f1) if gram is None else gram
    s2 = f1.rss / f1.dof
    key = [group_key(p) for p in f1.specs]
    idx = {g: [i for i in range(nb, len(key)) if key[i] == g] for g in groups}
    out: dict[str, float] = {}
    for g in groups:
        rest = list(range(nb)) + [i for h in groups if h != g for i in idx[h]]
        out[g] = _pvalue(A, b, idx[g], rest, s2)
    return out


def identifiable_groups(f1: FitResult, nb: int, alpha: float) -> tuple[set[str], dict[str, float]]:
    """The candidate's groups that backward elimination on eq. G1 keeps (see the module
    docstring), and the p-values of the last round (the kept groups' and the last dropped)."""
    groups = list(dict.fromkeys(group_key(p) for p in f1.specs[nb:]))
    thr = alpha / max(len(groups), 1)
    pv: dict[str, float] = {}
    gram = _gram(f1)
    while groups:
        pv = identifiable_pvalues(f1, nb, groups, gram)
        worst = max(groups, key=lambda g: pv[g])
        if pv[worst] < thr:
            break
        groups.remove(worst)
    return set(groups), pv

