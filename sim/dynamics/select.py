"""Forward selection of effects by the withheld torque error (eq. S1).

The score of a set of effects is the out-of-segment chi^2 (eq. S1)::

    chi2 = mean over samples and joints of ((tau_raw - tau0 - Y theta_(-seg)) / sigma_k)^2

with theta_(-seg) fitted without the time segment the sample lies in (and a guard of half a
filter window on each side). It is 1 when the model explains the torques down to the noise.
Each step adds the candidate that lowers it most, if the drop is at least ``min_rel`` of the
current chi2 and ``min_abs`` (noise variances): smaller drops are what a wrong friction law or
the acceleration filter leave, not evidence of an effect. One Stribeck speed a joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.dynamics.cvgram import CVGram
from sim.dynamics.effects import Effect
from zrp.arrays import F64

__all__ = ["Step", "chi2_of", "forward_select"]


@dataclass(frozen=True)
class Step:
    """One accepted effect and the withheld chi2 after it."""

    key: str
    chi2: float


def chi2_of(b_raw: F64, pred: F64, sigma: F64) -> float:
    return float(np.mean(((b_raw - pred) / sigma) ** 2))


def _family(e: Effect) -> tuple[str, int | None]:
    return e.name, e.joint


def forward_select(effects: list[Effect], b: F64, b_raw: F64, sigma: F64, *, folds: int,
                   guard: int, min_rel: float, min_abs: float, max_effects: int
                   ) -> tuple[list[Effect], list[Step], F64]:
    """The chosen effects, the steps (first: the nominal model, key "nominal") and the
    out-of-segment prediction of the final set (S, n)."""
    cv = CVGram(effects, b, sigma, folds, guard)
    chosen: list[Effect] = []
    pred = np.zeros_like(b)
    chi2 = chi2_of(b_raw, pred, sigma)
    steps = [Step("nominal", chi2)]
    while len(chosen) < max_effects:
        taken = {_family(e) for e in chosen}
        best: tuple[float, Effect, F64] | None = None
        for e in effects:
            if _family(e) in taken:
                continue
            p = cv.predict([c.key for c in (*chosen, e)])
            c = chi2_of(b_raw, p, sigma)
            if best is None or c < best[0]:
                best = (c, e, p)
        if best is None or chi2 - best[0] < max(min_rel * chi2, min_abs):
            break
        chi2, e, pred = best
        chosen.append(e)
        steps.append(Step(e.key, chi2))
    return chosen, steps, pred
