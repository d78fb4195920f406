"""The greedy search over motion effects (forward steps, then a backward check), on the
static engine's statistics: identifiability (:func:`~zrp.gap.fit.leastsq.check_identifiable`),
Wald tests per joint group, F test and BIC against the current model, and cross-validated RMS
over folds of whole time segments (:func:`~zrp.gap.fit.leastsq.cv_rms`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from zrp.arrays import I64
from zrp.gap.fit.leastsq import check_identifiable, cv_rms, f_test, group_key, wald_groups
from zrp.gap.model.context import EFFECTS
from zrp.gap.model.effects import effect_parameters
from zrp.gap.motion.effects import POSITIVE, effect_columns, linearise, plausible, tested
from zrp.gap.motion.fitting import Engine, ModelFit, named_joints
from zrp.gap.motion.profile import compliance_start, vibration_start

__all__ = ["Trial", "backward_check", "drop_effects", "greedy", "settle_compliance"]

#: the effects whose start values (and joints) come from a profile search
STARTS = {"residual_vibration": vibration_start, "dynamic_compliance": compliance_start}



@dataclass(frozen=True, eq=False)
class Trial:
    """One candidate effect tried on top of the current model.

    Attributes:
        effect: the candidate.
        fit: the fitted model with it (None when it could not be tried).
        joints: joints kept (0 for a parameter shared by all joints).
        cv_rms: cross-validated 3-D RMS (length unit), inf when not tried.
        p_value: F test against the current model.
        bic_delta: BIC change against the current model.
        note: why it was not tried or not significant.
    """

    effect: str
    fit: ModelFit | None
    joints: tuple[int, ...] = ()
    cv_rms: float = float("inf")
    p_value: float = 1.0
    bic_delta: float = 0.0
    note: str = ""
    aliased: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        return {"effect": self.effect, "joints": list(self.joints),
                "cv_rms": None if not np.isfinite(self.cv_rms) else self.cv_rms,
                "p_value": self.p_value, "bic_delta": self.bic_delta, "note": self.note,
                "aliased": list(self.aliased)}


def _candidate_specs(eng: Engine, effect: str, start: dict[str, float]) -> list:
    if effect in EFFECTS:
        return effect_parameters(eng.base_ctx, effect)[0]
    joints = named_joints(start) if effect in STARTS else None  # the joints profiled
    specs = linearise(effect_columns(eng.traj, effect, start, eng.torque, eng.terms,
                                     joints=joints))[1]
    if effect in STARTS:  # only the joints the profile search found the effect on
        specs = [s for s in specs if s.name in start]
    return specs


def _implausible_groups(eng: Engine, mf: ModelFit, first: int) -> set[str]:
    """The joint groups of the parameters from ``first`` on whose values are not the effect: a
    negative lag, friction, compliance or mode, a mode with zeta outside (0, 1) or a frequency
    the sampling cannot see."""
    rate = eng.traj.rate_hz
    return {group_key(s) for s, v in zip(mf.specs[first:], mf.result.theta[first:], strict=True)
            if v <= 0.0 or not plausible(s.name, float(v), rate)}


def _one_mode_per_joint(current: ModelFit, start: dict[str, float]) -> dict[str, float]:
    """A joint has one elastic mode: its compliance's spring-mass response (eq. M8) or a
    residual vibration (eq. M5), not both. Start values of the other one on a joint that
    already has one are dropped (the compliance stays, quasi-static; the mode is not offered)."""
    have = {s.joint for s in current.specs
            if s.name.endswith((".dyn_omega", ".vib_omega"))}
    out = {}
    for k, v in start.items():
        j = int(k[1:k.index(".")]) if k.startswith("q") else 0
        if j in have and k.endswith(("_omega", "_zeta", ".vib_gain")):
            continue
        out[k] = v
    return out


def settle_compliance(eng: Engine, mf: ModelFit, poses: I64) -> ModelFit:
    """A fitted model whose compliance responses (eq. M8) are all physical: those that left
    the range (a refit on other samples can drift there) become quasi-static."""
    if "dynamic_compliance" not in mf.effects:
        return mf
    return _quasi_static_fallback(eng, mf, eng.nreg, dict(mf.effects), poses)


def _start(eng: Engine, current: ModelFit, effect: str, poses: I64) -> dict[str, float]:
    """Start values (and joints) of a profiled effect (:data:`STARTS`); {} for the others."""
    if effect not in STARTS:
        return {}
    return _one_mode_per_joint(current, STARTS[effect](eng, current, poses))


def _quasi_static_fallback(eng: Engine, mf: ModelFit, first: int,
                           effects: dict[str, frozenset[str] | None], poses: I64) -> ModelFit:
    """Refit quasi-statically (-c tau) the compliant joints whose spring-mass response (eq. M8)
    left the physical range (zeta above the servo's, omega the sampling cannot see): its
    limit for omega -> infinity. ``effects`` is updated in place."""
    rate = eng.traj.rate_hz
    bad = {s.joint for s, v in zip(mf.specs[first:], mf.result.theta[first:], strict=True)
           if s.name.endswith((".dyn_omega", ".dyn_zeta")) and not plausible(s.name, v, rate)}
    if not bad:
        return mf
    drop = {f"q{k}.dyn_{x}" for k in bad for x in ("omega", "zeta")}
    keep = effects["dynamic_compliance"] or frozenset(
        s.name for s in mf.specs[first:] if s.effect == "dynamic_compliance")
    effects["dynamic_compliance"] = frozenset(keep - drop)
    values = {k: v for k, v in mf.values.items() if k not in drop}
    return eng.fit(effects, poses, values, mf.result.theta[:eng.nreg])


def try_effect(eng: Engine, current: ModelFit, effect: str, poses: I64,
               folds: Sequence[I64], alpha: float) -> Trial:
    """Fit ``effect`` on top of ``current``: identifiable parameters, Wald pruning of its
    joint groups at alpha / groups, then the scores."""
    start = _start(eng, current, effect, poses)
    cand = _candidate_specs(eng, effect, start)
    if not cand:
        return Trial(effect, None, note="no parameter applies to these data")
    keep, aliased = check_identifiable(current.ctx, current.result, cand, poses)
    al = tuple(a.name for a in aliased if a.dropped)
    if not keep:
        return Trial(effect, None, note="not identifiable on top of the current model",
                     aliased=al)
    first = len(current.specs)
    effects = {**current.effects, effect: frozenset(s.name for s in keep)}
    mf = eng.fit(effects, poses, {**current.values, **start},
                 current.result.theta[:eng.nreg])
    if effect == "dynamic_compliance":
        mf = _quasi_static_fallback(eng, mf, first, effects, poses)
    pw = wald_groups(mf.result, first, tested)
    sig = {g for g, p in pw.items() if p < alpha / max(len(pw), 1)}
    if effect in POSITIVE:
        sig -= _implausible_groups(eng, mf, first)
    if not sig:
        return Trial(effect, None, note="no joint group significant", aliased=al)
    if len(sig) < len(pw):
        names = frozenset(s.name for s in mf.specs[first:] if group_key(s) in sig)
        effects[effect] = names
        mf = eng.fit(effects, poses, mf.values, mf.result.theta[:eng.nreg])
    joints = tuple(sorted({s.joint for s in mf.specs[first:]}))
    return Trial(effect, mf, joints, cv_rms(mf.ctx, mf.result, folds),
                 f_test(current.result, mf.result), mf.result.bic - current.result.bic,
                 aliased=al)


def refine_compliance(eng: Engine, current: ModelFit, cur_cv: float, poses: I64,
                      folds: Sequence[I64], alpha: float) -> tuple[ModelFit, float]:
    """Give the quasi-static compliant joints of ``current`` their spring-mass response (eq. M8)
    when, now that other effects are modelled (e.g. friction on the same joint), the profile
    screen passes and the refit is significant (F test, BIC, CV RMS: the rules of a step)."""
    keep = current.effects.get("dynamic_compliance", frozenset())
    if keep is None or not keep:
        return current, cur_cv
    start = _one_mode_per_joint(current, compliance_start(eng, current, poses))
    new = {k: v for k, v in start.items()
           if k.endswith((".dyn_omega", ".dyn_zeta")) and k.replace(
               k[k.rindex("_"):], "_compliance") in keep and k not in keep}
    if not new:
        return current, cur_cv
    effects = {**current.effects, "dynamic_compliance": frozenset(keep | set(new))}
    mf = eng.fit(effects, poses, {**current.values, **new}, current.result.theta[:eng.nreg])
    mf = _quasi_static_fallback(eng, mf, eng.nreg, effects, poses)
    if effects["dynamic_compliance"] == keep:
        return current, cur_cv
    cv = cv_rms(mf.ctx, mf.result, folds)
    if (f_test(current.result, mf.result) < alpha and mf.result.bic < current.result.bic
            and cv < cur_cv):
        return mf, cv
    return current, cur_cv


def _trials(eng: Engine, current: ModelFit, left: Sequence[str], poses: I64,
            folds: Sequence[I64], alpha: float) -> list[Trial]:
    """``try_effect`` of each candidate, keeping the fit of the best so far only (the lowest
    CV RMS; the first of equals, as the stable sort ranks them): each fit holds arrays of the
    whole trajectory (bases, shifts), so holding every candidate's fit until the ranking made
    the search the diagnosis' memory peak (memory linear in the samples per fit kept)."""
    out: list[Trial] = []
    best = -1
    for e in left:
        tr = try_effect(eng, current, e, poses, folds, alpha)
        if best < 0 or tr.cv_rms < out[best].cv_rms:
            if best >= 0:
                out[best] = replace(out[best], fit=None)
            best = len(out)
        else:
            tr = replace(tr, fit=None)
        out.append(tr)
    return out


def greedy(eng: Engine, start: ModelFit, effects: Sequence[str], poses: I64,
           folds: Sequence[I64], alpha: float = 1e-3, min_gain: float = 0.01,
           max_steps: int = 3) -> tuple[ModelFit, list[tuple[Trial, list[Trial]]]]:
    """Add the best effect (lowest CV RMS) while its F test is significant, BIC falls and the
    CV RMS improves by at least ``min_gain``. Returns the final model and, per step, the
    winner and the ranking."""
    current = start
    cur_cv = cv_rms(start.ctx, start.result, folds)
    steps: list[tuple[Trial, list[Trial]]] = []
    for _ in range(max_steps):
        left = [e for e in effects if e not in current.effects]
        if not left:
            break
        ranked = sorted(_trials(eng, current, left, poses, folds, alpha),
                        key=lambda tr: tr.cv_rms)
        best = ranked[0]
        light = ranked[1:]
        if (best.fit is None or best.p_value >= alpha or best.bic_delta >= 0
                or best.cv_rms > (1.0 - min_gain) * cur_cv):
            steps.append((Trial(best.effect, None, note="stop"),
                          [replace(best, fit=None), *light]))
            break
        steps.append((best, [best, *light]))
        current, cur_cv = best.fit, best.cv_rms
        current, cur_cv = refine_compliance(eng, current, cur_cv, poses, folds, alpha)
    return current, steps


def backward_check(eng: Engine, mf: ModelFit, poses: I64, alpha: float) -> ModelFit:
    """Drop the joint groups that the final joint model no longer needs (Wald test at
    alpha / groups) and refit; drop an effect left without parameters."""
    pw = wald_groups(mf.result, eng.nreg, tested)
    sig = {g for g, p in pw.items() if p < alpha / max(len(pw), 1)}
    if len(sig) == len(pw):
        return mf
    effects: dict[str, frozenset[str] | None] = {}
    for e in mf.effects:
        names = frozenset(s.name for s in mf.specs[eng.nreg:]
                          if s.effect == e and group_key(s) in sig)
        if names:
            effects[e] = names
    return eng.fit(effects, poses, mf.values, mf.result.theta[:eng.nreg])


def drop_effects(eng: Engine, mf: ModelFit, poses: I64, alpha: float) -> ModelFit:
    """Backward elimination of whole effects: an effect whose removal does not make the fit
    significantly worse (F test p >= alpha, or a lower BIC without it) is dropped - e.g. a
    servo lag on every joint that stood in for a sync delay found later."""
    changed = True
    while changed and len(mf.effects) > 1:
        changed = False
        for e in list(mf.effects):
            rest = {k: v for k, v in mf.effects.items() if k != e}
            small = eng.fit(rest, poses, mf.values, mf.result.theta[:eng.nreg])
            if f_test(small.result, mf.result) >= alpha or small.result.bic < mf.result.bic:
                mf, changed = small, True
                break
    return mf
