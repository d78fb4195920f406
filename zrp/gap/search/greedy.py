"""Which effect: the greedy forward search over the effect library, then a backward pass.

At each step every effect not yet in the model is fitted on top of it (the parameters the data
can identify; joints whose parameters fail a Wald test are pruned), the candidates are ranked
by cross-validated RMS, and the best is added when its F test is significant, its BIC falls and
its CV RMS improves by at least ``min_gain`` (``thermal_expansion`` also when the temperature
explains what a common scale of the links cannot, :mod:`zrp.gap.search.lookalike`). The
withheld poses only judge each step.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.analysis.checks import GapWarning
from zrp.gap.analysis.excitation import excited_only
from zrp.gap.analysis.identifiability import GEOMETRIC, geometric_overlap
from zrp.gap.fit.aliasing import Aliased
from zrp.gap.fit.constrained import HELD_AT_SUM_0, n_registration, within_domains
from zrp.gap.fit.heldwald import group_pvalues
from zrp.gap.fit.leastsq import (
    FitResult,
    cv_rms,
    f_test,
    fit,
    group_key,
    identifiable_start,
    wald_groups,
)
from zrp.gap.fit.metrics import Metrics
from zrp.gap.fit.profiles import switch_bands, with_backlash_switch
from zrp.gap.fit.sumzero import fit_sum_zero, held_joints, summed_groups
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.domains import SUMMED, domain_key
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem
from zrp.gap.search.lookalike import temperature_needed
from zrp.gap.search.progress import progress_bar
from zrp.gap.search.steps import BacklashSwitch, Candidate, Step, parameter_estimates

__all__ = ["TIE_TOL", "SearchResult", "SearchSettings", "backward_pass", "greedy_search",
           "withheld_residual"]

Folds = Sequence[NDArray[np.int64]]
#: candidates whose cross-validated RMS is within this fraction of the winner's are reported
#: as indistinguishable from it.
TIE_TOL = 0.01


@dataclass(frozen=True)
class SearchSettings:
    """What the search needs besides the data: the poses, the starting rotation and the tests.

    Attributes:
        fitting, withheld: pose indices; folds: the CV folds of the fitting poses.
        rb0: initial instrument-from-base rotation of every fit.
        alpha, min_gain, max_steps: see :func:`zrp.gap.diagnose`.
        progress: show progress (a bar on a terminal, periodic lines otherwise).
        resolution: numerical resolution of the fits (length unit); a model that fits the
            fitting poses to within it is not improved further (noise-free data).
    """

    fitting: NDArray[np.int64]
    withheld: NDArray[np.int64]
    folds: Folds
    rb0: F64
    alpha: float
    min_gain: float
    max_steps: int
    progress: bool = False
    resolution: float = 0.0


@dataclass(frozen=True)
class SearchResult:
    """The steps added, the final fit and what was reported on the way.

    Attributes:
        steps: effects added, in order.
        final_fit: the final model (after the backward pass).
        aliased: parameters of the added effects the data cannot tell apart from others.
        backlash: the flank model of ``backlash`` when it was added.
        last_candidates: the candidates of the step at which the search stopped, or None.
        pruned: significance groups dropped in the backward pass.
    """

    steps: tuple[Step, ...]
    final_fit: FitResult
    aliased: tuple[Aliased, ...]
    backlash: BacklashSwitch | None
    last_candidates: tuple[Candidate, ...] | None
    pruned: tuple[str, ...]


@dataclass(frozen=True)
class _Trial:
    """One effect fitted on top of the current model (``fit`` None when it was not)."""

    candidate: Candidate
    fit: FitResult | None
    aliased: list[Aliased]
    backlash: BacklashSwitch | None = None


def withheld_residual(ctx: Context, result: FitResult, poses: NDArray[np.int64]) -> F64:
    """Residual of the fitted model on other poses (the withheld ones), shape (3R,)."""
    return Problem(ctx, result.specs, poses, result.base_rotation).residual(result.theta)


def _not_tried(effect: str, note: str, aliased: list[Aliased] | None = None) -> _Trial:
    return _Trial(Candidate(effect, (), 0, math.nan, math.nan, 1.0, False, note), None,
                  aliased or [])


def _significant(ctx: Context, current: FitResult, f1: FitResult, keep: list[ParamSpec],
                 s: SearchSettings) -> tuple[FitResult, list[ParamSpec]]:
    """The candidate's parameters whose group is significant (:mod:`zrp.gap.fit.heldwald`,
    eq. H2: near-collinear groups that a held combination spans, each needed by the data, are
    not lost to the prior variance that combination gives them), refitted without the others
    when some were pruned."""
    nb = len(current.specs)
    pv = group_pvalues(f1, nb, s.alpha)
    thr = s.alpha / max(len(pv), 1)
    sig = {g for g, p in pv.items() if p < thr}
    kept = [p for p in keep if group_key(p) in sig]
    if kept and len(kept) < len(keep):
        idx = [nb + i for i, p in enumerate(keep) if group_key(p) in sig]
        f1 = fit(ctx, list(current.specs) + kept, s.fitting,
                 np.concatenate([f1.theta[:nb], f1.theta[idx]]), s.rb0)
    return f1, kept


def _try_effect(ctx: Context, current: FitResult, current_cv: float, effect: str,
                specs: list[ParamSpec], why: str | None, s: SearchSettings) -> _Trial:
    """Fit ``effect`` on top of ``current`` and judge it (F test, BIC, CV RMS gain)."""
    if not specs:
        return _not_tried(effect, f"not tried: {why}")
    keep, aliased, start = identifiable_start(ctx, current, specs)
    if not keep:
        return _not_tried(effect, "no parameter identifiable on top of the current model",
                          aliased)
    f1 = fit(ctx, list(current.specs) + keep, s.fitting,
             np.concatenate([current.theta, np.zeros(len(keep))]), s.rb0, start=start)
    f1, kept = _significant(ctx, current, f1, keep, s)
    if not kept:
        return _Trial(Candidate(effect, (), 0, cv_rms(ctx, f1, s.folds), f1.bic - current.bic,
                                f_test(current, f1), False, "no joint significant"),
                      None, aliased)
    f1, own, others = _in_domains(ctx, f1, specs, s)
    kept = [p for p in f1.specs if p.effect == effect]
    if not kept:
        return _Trial(Candidate(effect, (), 0, math.nan, math.nan, 1.0, False,
                                "fitted values outside the physical domain: "
                                + "; ".join(own)), None, aliased)
    cv = cv_rms(ctx, f1, s.folds)
    pval = f_test(_nested(ctx, current, f1, s), f1)
    dbic = f1.bic - current.bic
    joints = tuple(sorted({p.joint for p in kept if p.joint > 0}))
    ok, note = _judged(pval, dbic, cv / current_cv if current_cv > 0 else math.inf, s, own,
                       others)
    if ok and effect == "thermal_expansion":  # not a common scale of the links in disguise
        ok, _, why = temperature_needed(ctx, current, f1, s.fitting, s.rb0, s.alpha)
        note = "; ".join(filter(None, [why, note]))
    return _Trial(Candidate(effect, joints, len(kept), cv, dbic, pval, ok, note), f1, aliased)


def _judged(pval: float, dbic: float, cv_ratio: float, s: SearchSettings, own: list[str],
            others: list[str]) -> tuple[bool, str]:
    """Whether a candidate passes (F test, BIC, CV gain) and its note."""
    ok = pval < s.alpha and dbic < 0 and cv_ratio < 1.0 - s.min_gain
    note = "" if ok else ("F test not significant" if pval >= s.alpha else
                          "BIC does not improve" if dbic >= 0 else
                          f"cross-validated RMS improves by less than {s.min_gain:.0%}")
    out = [w for w in own if HELD_AT_SUM_0 not in w]
    held = [w for w in own if HELD_AT_SUM_0 in w]
    return ok, "; ".join(filter(None, [
        note, out and "parameters taken out, outside the physical domain: " + "; ".join(out),
        held and "held at the bound of the physical domain: " + "; ".join(held),
        others and "earlier parameters taken out or held, outside their domains: "
        + "; ".join(others)]))


def _in_domains(ctx: Context, f1: FitResult, specs: list[ParamSpec], s: SearchSettings
                ) -> tuple[FitResult, list[str], list[str]]:
    """``f1`` inside the physical domains (:func:`~zrp.gap.fit.constrained.within_domains`),
    with the reasons for the candidate's own parameters taken out and the names of earlier
    ones taken out."""
    f1, outside = within_domains(ctx, f1, n_registration(f1.specs), s.fitting, s.rb0)
    own_names = {p.name for p in specs}
    own_joints = {p.name.split(".", 1)[0] for p in specs
                  if domain_key(p.name, p.effect) in SUMMED}
    held = [w for w in outside if HELD_AT_SUM_0 in w]
    own = [w for w in outside if w.split(" = ")[0] in own_names
           or (w in held and w.split(" ", 1)[0] in own_joints)]
    others = [w.split(" outside ")[0].split(" (")[0] for w in outside if w not in own]
    return f1, own, others


def _nested(ctx: Context, current: FitResult, f1: FitResult, s: SearchSettings) -> FitResult:
    """The model the F test compares ``f1`` with: ``current``, or, when the domains took some
    of its parameters out of ``f1`` or held lumped weights at sum 0 there, ``current``
    refitted without them or with them held (nested in ``f1``)."""
    names = {p.name for p in f1.specs}
    idx = [i for i, p in enumerate(current.specs) if p.name in names]
    if len(idx) == len(current.specs) and held_joints(f1) <= held_joints(current):
        return current
    specs = [current.specs[i] for i in idx]
    groups = summed_groups(specs)
    held = {j for j in held_joints(f1) | held_joints(current) if len(groups.get(j, ())) > 1}
    return fit_sum_zero(ctx, specs, held, s.fitting, current.theta[idx], s.rb0)


def _try_backlash(ctx: Context, current: FitResult, current_cv: float,
                  s: SearchSettings) -> _Trial:
    """``backlash`` with its flank model profiled on top of the current model."""
    ctx_b = with_backlash_switch(ctx, current, s.fitting)
    specs, why = excited_only(ctx_b, effect_parameters(ctx_b, "backlash"))
    switch = ctx_b.backlash_switch or ()
    flank = BacklashSwitch(tuple(None if not np.isfinite(v) else v for v in switch),
                           tuple(switch_bands(ctx_b.backlash_switch_weights)),
                           ctx_b.payload_kg, tuple(ctx_b.backlash_lead or ()),
                           ctx_b.backlash_switch_weights)
    trial = _try_effect(ctx, current, current_cv, "backlash", specs, why, s)
    return _Trial(trial.candidate, trial.fit, trial.aliased, flank)


def _ranked(trials: list[_Trial]) -> list[_Trial]:
    """Significant candidates first, then by cross-validated RMS (untried last)."""
    return sorted(trials, key=lambda t: (not t.candidate.significant,
                                         math.inf if math.isnan(t.candidate.cv_rms)
                                         else t.candidate.cv_rms))


def _step(ctx: Context, current: FitResult, best: _Trial, ranked: list[_Trial], n_step: int,
          withheld: NDArray[np.int64]) -> Step:
    """The step that adds ``best`` to ``current`` (warns when others tie with it)."""
    cand, f_new = best.candidate, best.fit
    assert f_new is not None
    overlap = (geometric_overlap(ctx, current, f_new.residual - current.residual)
               if cand.effect not in GEOMETRIC else math.nan)
    ties = tuple(t.candidate.effect for t in ranked[1:] if t.candidate.significant
                 and t.candidate.cv_rms <= cand.cv_rms * (1.0 + TIE_TOL))
    if ties:
        warnings.warn(f"step {n_step}: {', '.join(ties)} fit(s) the data as well as "
                      f"{cand.effect} (cross-validated RMS within {TIE_TOL:.0%}); these "
                      "data cannot tell the effects apart", GapWarning, stacklevel=2)
    after = withheld_residual(ctx, f_new, withheld)
    return Step(cand.effect, cand.joints, parameter_estimates(f_new, len(current.specs)),
                Metrics.of(after), Metrics.of(f_new.residual), cand.cv_rms, cand.p_value,
                cand.bic_delta, tuple(t.candidate for t in ranked), tuple(best.aliased),
                overlap, ties)


def greedy_search(ctx: Context, reg: FitResult, effects: Sequence[str],
                  specs_of: Mapping[str, tuple[list[ParamSpec], str | None]],
                  s: SearchSettings) -> SearchResult:
    """Add effects to the registration ``reg`` one at a time (see the module docstring),
    then drop what the final model no longer needs (:func:`backward_pass`)."""
    current, current_cv = reg, cv_rms(ctx, reg, s.folds)
    steps: list[Step] = []
    aliased: list[Aliased] = []
    backlash: BacklashSwitch | None = None
    last: tuple[Candidate, ...] | None = None
    bar = progress_bar(s.max_steps * len(effects), "diagnose", s.progress)
    for _ in range(s.max_steps):
        if Metrics.of(current.residual).rms <= s.resolution:
            break  # fits to numerical precision: nothing left to explain
        trials = []
        for eff in effects:
            bar.update(1)
            if eff in {st.effect for st in steps}:
                continue
            if eff == "backlash":  # which flank: profiled on top of the current model
                trials.append(_try_backlash(ctx, current, current_cv, s))
            else:
                specs, why = specs_of[eff]
                trials.append(_try_effect(ctx, current, current_cv, eff, specs, why, s))
        ranked = _ranked(trials)
        best = ranked[0] if ranked else None
        if best is None or not best.candidate.significant or best.fit is None:
            last = tuple(t.candidate for t in ranked) if ranked else None
            break
        if best.backlash is not None:
            backlash = best.backlash
        aliased += best.aliased
        steps.append(_step(ctx, current, best, ranked, len(steps) + 1, s.withheld))
        current, current_cv = best.fit, best.candidate.cv_rms
    bar.close()
    final, pruned = backward_pass(ctx, current, len(reg.specs), s)
    _warn_dropped(steps, aliased)
    return SearchResult(tuple(steps), final, tuple(aliased), backlash, last, pruned)


def _warn_dropped(steps: Sequence[Step], aliased: Sequence[Aliased]) -> None:
    """Name, per effect added, the parameters that were not estimated separately."""
    for st in steps:
        dropped = [a for a in aliased if a.dropped and a.effect == st.effect]
        if dropped:
            pairs = "; ".join(f"{a.name} ~ {'/'.join(a.partners) or 'nothing (no effect)'}"
                              for a in dropped)
            warnings.warn(f"{st.effect}: {len(dropped)} parameter(s) cannot be told apart from "
                          f"others with these data and were not estimated separately: {pairs}",
                          GapWarning, stacklevel=2)


def backward_pass(ctx: Context, current: FitResult, nreg: int, s: SearchSettings
                  ) -> tuple[FitResult, tuple[str, ...]]:
    """Drop the joints that an effect picked up while another effect was still missing, when
    the final model no longer needs them (Wald test at alpha / groups); returns the refitted
    model and the groups dropped.

    The plain Wald test, not eq. H2 of the forward steps (:mod:`zrp.gap.fit.heldwald`): of
    near-collinear groups that a step took in together, held together, one is dropped here
    and the refit estimates the other. Backward elimination one group at
    a time: the least significant group goes, the model is
    refitted and the tests are redone. Dropping every group above the threshold at once
    removed groups that are each insignificant only because they stand in for one another
    (a joint's offset and its encoder scale over a narrow range of that joint, an axis tilt and
    an offset) while the model needs one of them: tests/gap/test_backward_pass.py, where the
    residual sum of squares grew 240-fold."""
    pruned: list[str] = []
    while len(current.specs) > nreg:
        pv = wald_groups(current, nreg)
        thr = s.alpha / max(len(pv), 1)
        worst = max(pv, key=lambda g: pv[g]) if pv else None
        if worst is None or pv[worst] < thr:
            break
        keep_idx = [i for i, p in enumerate(current.specs)
                    if i < nreg or group_key(p) != worst]
        pruned.append(worst)
        current = fit(ctx, [current.specs[i] for i in keep_idx], s.fitting,
                      current.theta[keep_idx], s.rb0)
        current, _ = within_domains(ctx, current, nreg, s.fitting, s.rb0)
    return current, tuple(pruned)
