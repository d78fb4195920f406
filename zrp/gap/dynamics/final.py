"""The final model, held to the standard identification: the baseline fitted in the same run
(:mod:`zrp.gap.dynamics.baseline`), the completion of a selected model that is clearly worse
than it on the withheld segments (eq. B0), and which effects are findings and which are small
(each one's rise of the withheld chi2 when left out of the final set)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.baseline import standard_effects
from zrp.gap.dynamics.cvgram import CVGram
from zrp.gap.dynamics.effects import Effect, inertial_correction
from zrp.gap.dynamics.fit import design, solve
from zrp.gap.dynamics.gate import Fitted, Gated, physical_gate
from zrp.gap.dynamics.options import DynamicsOptions
from zrp.gap.dynamics.results import Baseline, FoundEffect, Param
from zrp.gap.dynamics.select import KEPT, Step, chi2_of
from zrp.gap.dynamics.states import States

__all__ = ["Setup", "baseline_fit", "not_worse", "small_effects"]


@dataclass(frozen=True)
class Setup:
    """Steps 1-3 and the candidates: the states, the residual torques (filtered and raw),
    the noise estimate and the weights of the fit (1 on a joint that is not data)."""

    s: States
    stride: int
    b: F64
    b_raw: F64
    noise: F64
    sigma: F64
    effects: list[Effect]


def baseline_fit(arm: Arm, su: Setup, opt: DynamicsOptions, guard: int
              ) -> tuple[Baseline, F64]:
    """The standard identification (:mod:`zrp.gap.dynamics.baseline`) on the same samples
    and withheld segments: unconstrained least squares, as the field fits it (its link
    combinations are a score, never written to a file); and its withheld prediction."""
    std = standard_effects(su.effects)
    pred = CVGram(std, su.b, su.sigma, opt.folds, guard).predict([e.key for e in std])
    d = design(std, *su.b.shape)
    theta = solve(d, su.b, su.sigma, with_cov=False).theta
    found, phi = [], {}
    for e, sl in zip(std, d.slices, strict=True):
        if e.name == "inertial" and e.basis is not None:
            phi = {b: p - arm.body_params(b)
                   for b, p in inertial_correction(arm, theta[sl], e.basis).items()}
            continue
        params = {p: Param(float(theta[sl][i]), float(theta[sl][i]), float(theta[sl][i]),
                           e.units[i]) for i, p in enumerate(e.params)}
        found.append(FoundEffect(e.key, e.name, e.joint, e.detail, params, 0.0))
    r = su.b_raw - pred
    return Baseline(keys=tuple(e.key for e in std), effects=found, phi_change=phi,
                    chi2=chi2_of(su.b_raw, pred, su.sigma),
                    rms_withheld=np.sqrt(np.mean(r * r, axis=0))), pred


def not_worse(arm: Arm, su: Setup, opt: DynamicsOptions, guard: int, steps: list[Step],
               selected: Gated) -> tuple[Baseline, list[Effect], Fitted, list[str]]:
    """The final model never worse on the withheld segments than the standard
    identification (eq. B0), in noise units (chi2) and in N m over the joints (what the
    report gives): when the selected effects lose to it clearly (by the selection's own
    threshold, ``min_rel``), they are completed with its terms, said in the notes."""
    base, base_pred = baseline_fit(arm, su, opt, guard)
    chosen, fitted, notes = selected
    score, ref = _scores(su, fitted.pred), _scores(su, base_pred)
    if all(r >= x * (1.0 - opt.min_rel) for r, x in zip(ref, score, strict=True)):
        return base, chosen, fitted, notes
    taken = {(e.name, e.joint) for e in chosen}
    more = [e for e in standard_effects(su.effects) if (e.name, e.joint) not in taken]
    union = physical_gate(arm, chosen + more, steps, su.b, su.sigma, opt, guard, None)
    got = _scores(su, union[1].pred)
    if not all(g <= x for g, x in zip(got, score, strict=True)):
        return base, chosen, fitted, [*notes, (
            f"the standard identification predicts the withheld segments better (chi2 "
            f"{ref[0]:.3g}, {ref[1]:.3g} N m against {score[0]:.3g}, {score[1]:.3g} N m) but "
            f"not once physical with the selected effects (chi2 {got[0]:.3g}, {got[1]:.3g} "
            "N m): the selected effects are kept")]
    added = [e.key for e in union[0] if e.key not in {c.key for c in chosen}]
    why = (f"the selected effects alone predict the withheld segments worse than the standard "
           f"identification (chi2 {score[0]:.3g}, {score[1]:.3g} N m against {ref[0]:.3g}, "
           f"{ref[1]:.3g} N m); completed with its terms {', '.join(added) or '-'} (now chi2 "
           f"{got[0]:.3g}, {got[1]:.3g} N m)")
    return base, union[0], union[1], [*notes, *union[2], why]


def _scores(su: Setup, pred: F64) -> tuple[float, float]:
    """The withheld chi2 and the withheld RMS over the joints (N m) of a prediction (a
    joint whose torque is not data has no residual: it counts as zero in both)."""
    r = su.b_raw - pred
    return chi2_of(su.b_raw, pred, su.sigma), float(np.sqrt(np.mean(r * r)))


def small_effects(chosen: list[Effect], found: list[FoundEffect], su: Setup,
                  opt: DynamicsOptions, guard: int) -> list[FoundEffect]:
    """Each effect's withheld chi2 drop in the final set (the rise without it, the others
    refitted); one below the selection's threshold is small: in the model, not a finding. A
    part of the model (payload, a part not on the arm) is weighed without the link
    combinations, which can carry any body's torques (the selection named the part)."""
    if not chosen:
        return found
    cv = CVGram(chosen, su.b, su.sigma, opt.folds, guard)
    keys = [e.key for e in chosen]
    full = chi2_of(su.b_raw, cv.predict(keys), su.sigma)
    limit = max(opt.min_rel * full, opt.min_abs)
    drops = {}
    for e in chosen:
        with_ = [k for k in keys if e.name not in KEPT or not k.startswith("inertial")]
        ref = full if len(with_) == len(keys) else chi2_of(su.b_raw, cv.predict(with_),
                                                            su.sigma)
        drops[e.key] = chi2_of(su.b_raw, cv.predict([k for k in with_ if k != e.key]),
                               su.sigma) - ref
    return [replace(f, chi2_drop=drops.get(f.key, f.chi2_drop),
                    small=drops.get(f.key, np.inf) < limit) for f in found]
