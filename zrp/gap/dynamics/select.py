"""Forward selection of effects by the withheld torque error (eq. S1).

The score of a set of effects is the out-of-segment chi^2 (eq. S1)::

    chi2 = mean over samples and joints of ((tau_raw - tau0 - Y theta_(-seg)) / sigma_k)^2

with theta_(-seg) fitted without the time segment the sample lies in (and a guard of half a
filter window on each side). It is 1 when the model explains the torques down to the noise.
Each step adds the candidate that lowers it most, if the drop is at least ``min_rel`` of the
current chi2 and ``min_abs`` (noise variances): smaller drops are what a wrong friction law or
the acceleration filter leave, not evidence of an effect. Parsimony: among the candidates whose
drop is within ``occam`` (10 %) of the largest, the one with the fewest parameters is taken (a
payload is also a change of the tool link's inertias; the four payload parameters are
preferred to the forty link combinations when both explain the torques), and a torque gain
gives way to an effect of the arm's masses in the same window (a hand the arm does not carry
looks like gains on every joint it loads). The link inertias' forty combinations yield to one
part or link (payload, absent part, one link's mass) that explains at least half of their
drop: a hand that is not mounted is named as such, the rest of what the links explain comes at
a later step. One Stribeck speed a joint; one change a part or link.

Forward steps are greedy: an effect taken early (a link's mass on the shoulder, which also
adds inertia about joint 1) can be the wrong story once the later effects are in (the rotor
inertia of joint 1). So the selection ends with exchanges (:func:`exchange`): a chosen effect
is taken out, or replaced by one not chosen with at most as many parameters, whenever that
lowers the withheld chi2; each exchange is a step of its own (``Step.replaces``), so the final
set is never worse on the withheld segments than any set the selection passed through. A
part of the model named as such (a payload, a part not on the arm) is never exchanged: once
the link combinations are in, they can carry its torques too, and the log cannot tell the
two apart; the forward rule has already preferred the part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.cvgram import CVGram
from zrp.gap.dynamics.effects import Effect

__all__ = ["Step", "chi2_of", "forward_select"]


@dataclass(frozen=True)
class Step:
    """One accepted effect, the withheld chi2 after it, and the other candidates whose drop
    was within the parsimony window of the best (the log cannot tell them from it)."""

    key: str
    chi2: float
    ties: tuple[str, ...] = ()
    replaces: str = ""  # an exchange: the effect taken out for this one ("" when added)


def chi2_of(b_raw: F64, pred: F64, sigma: F64) -> float:
    return float(np.mean(((b_raw - pred) / sigma) ** 2))


#: Effects of the arm's masses: a torque gain is named only when none of them explains the
#: same torques (a common gain is the symptom of a wrong mass, not a sensor finding).
PHYSICAL = ("payload", "absent_part", "link_mass", "inertial")

#: The share of the link inertias' withheld drop that one part or link of the model
#: (a payload, an absent part, one link's mass) must explain to be named before them.
LUMPED = 0.5


def _family(e: Effect) -> tuple[str, int | None, str]:
    """One effect a family: per joint, or per part or link for the body effects."""
    return e.name, e.joint, e.detail if e.name in ("absent_part", "link_mass") else ""


def _tag(e: Effect) -> str:
    return e.key if e.name in ("absent_part", "link_mass") else e.key.split("@")[0]


def _rank(e: Effect, near: set[str]) -> int:
    """Among near-equal candidates, what gives way: a torque gain to any effect of the
    masses, a link's mass to a payload or a part at the tool (a gripper is the likelier
    story than a wrist link's mass where the log cannot tell them apart)."""
    if e.name == "gain":
        return int(bool(near & set(PHYSICAL)))
    if e.name == "link_mass":
        return int(bool(near & {"payload", "absent_part"}))
    return 0


def _parsimonious(scored: list[tuple[float, Effect, F64]], chi2: float, occam: float
                  ) -> tuple[tuple[float, Effect, F64] | None, tuple[str, ...]]:
    """The candidate with the fewest parameters among those within ``occam`` of the best
    drop (ties: the lower chi2), and the other families within that window."""
    if not scored:
        return None, ()
    top = min(c for c, _, _ in scored)
    near = [s for s in scored if chi2 - s[0] >= (1.0 - occam) * (chi2 - top)]
    if all(s[1].name == "inertial" for s in near):
        # every link's forty combinations yield to one part or link of the model that
        # explains at least LUMPED of their drop (the rest is left for the next steps)
        lumped = [s for s in scored if s[1].name in ("payload", "absent_part", "link_mass")
                  and chi2 - s[0] >= LUMPED * (chi2 - top)]
        near += lumped
    names = {s[1].name for s in near}
    best = min(near, key=lambda s: (_rank(s[1], names), s[1].columns.shape[-1], s[0]))
    others = {_tag(s[1]) for s in near if _family(s[1]) != _family(best[1])}
    return best, tuple(sorted(others))


def forward_select(effects: list[Effect], b: F64, b_raw: F64, sigma: F64, *, folds: int,
                   guard: int, min_rel: float, min_abs: float, max_effects: int,
                   occam: float = 0.1) -> tuple[list[Effect], list[Step], F64]:
    """The chosen effects, the steps (first: the nominal model, key "nominal") and the
    out-of-segment prediction of the final set (S, n)."""
    cv = CVGram(effects, b, sigma, folds, guard)
    chosen: list[Effect] = []
    pred = np.zeros_like(b)
    chi2 = chi2_of(b_raw, pred, sigma)
    steps = [Step("nominal", chi2)]
    while len(chosen) < max_effects:
        taken = {_family(e) for e in chosen}
        scored = [(chi2_of(b_raw, p, sigma), e, p) for e in effects if _family(e) not in taken
                  for p in [cv.predict([c.key for c in (*chosen, e)])]]
        best, ties = _parsimonious(scored, chi2, occam)
        if best is None or chi2 - best[0] < max(min_rel * chi2, min_abs):
            break
        chi2, e, pred = best
        chosen.append(e)
        steps.append(Step(e.key, chi2, ties))
    chosen, swaps, pred = exchange(cv, effects, chosen, b_raw, sigma, chi2, pred)
    return chosen, steps + swaps, pred


#: An exchange is taken when it lowers the withheld chi2 by at least this share.
EXCHANGE = 1e-3

#: Never exchanged (module docstring).
KEPT = ("payload", "absent_part")


def _best_exchange(cv: CVGram, effects: list[Effect], chosen: list[Effect], b_raw: F64,
                   sigma: F64) -> tuple[float, int, Effect | None, F64] | None:
    """The best removal or replacement of one chosen effect: (chi2, index out, effect in or
    None, prediction)."""
    best = None
    for i, out in enumerate(chosen):
        if out.name in KEPT:
            continue
        rest = chosen[:i] + chosen[i + 1:]
        taken = {_family(e) for e in rest}
        keys = [c.key for c in rest]
        p_out = out.columns.shape[-1]
        for e in [None, *(e for e in effects if _family(e) not in taken and e is not out
                          and e.columns.shape[-1] <= p_out)]:
            p = cv.predict(keys if e is None else [*keys, e.key])
            c = chi2_of(b_raw, p, sigma)
            if best is None or c < best[0]:
                best = (c, i, e, p)
    return best


def exchange(cv: CVGram, effects: list[Effect], chosen: list[Effect], b_raw: F64, sigma: F64,
             chi2: float, pred: F64) -> tuple[list[Effect], list[Step], F64]:
    """Take out or replace chosen effects while that lowers the withheld chi2 (module
    docstring); the final set, the exchange steps and its prediction."""
    steps: list[Step] = []
    for _ in range(2 * len(chosen)):
        best = _best_exchange(cv, effects, chosen, b_raw, sigma)
        if best is None or best[0] > chi2 * (1.0 - EXCHANGE):
            break
        chi2, i, e, pred = best
        out = chosen[i]
        chosen = chosen[:i] + chosen[i + 1:] + ([] if e is None else [e])
        steps.append(Step("-" if e is None else e.key, chi2, (), out.key))
    return chosen, steps, pred
