"""The chosen effects fitted, physical: the bounded least squares of the effects on the whole
log with 95 % intervals (eq. F2), the link inertias physically consistent by construction
(eq. P1) when chosen, the bodies they change (eq. R5), and the gate that drops an effect
which would leave a body non-physical (the latest chosen culprit; the link combinations
first) or that the final fit leaves at nothing (:func:`physical_gate`)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.effects import Effect
from zrp.gap.dynamics.fit import cross_validate, design, solve
from zrp.gap.dynamics.options import DynamicsOptions
from zrp.gap.dynamics.physical import InertialFit, physical_cross_validate, physical_fit
from zrp.gap.dynamics.resulting import BodyChange, ChangedArm, link_changes, resulting_bodies
from zrp.gap.dynamics.results import FoundEffect, Param
from zrp.gap.dynamics.select import Step

__all__ = ["BODY_CHANGES", "IDLE", "Fitted", "Gated", "fit_chosen", "physical_gate"]

#: An effect whose torques stay under this share of the noise on every joint in the final fit
#: is left out (another effect took them).
IDLE = 0.05

#: The effects that change a body of the model (their resulting bodies must be physical).
BODY_CHANGES = ("payload", "absent_part", "link_mass")


def params_of(e: Effect, theta: F64, cov: F64, at_bound: np.ndarray) -> dict[str, Param]:
    """The fitted parameters with 95 % intervals, each held inside its domain (an interval
    never reaches values the parameter cannot have)."""
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {p: Param(float(theta[i]), float(max(theta[i] - 1.96 * sd[i], e.lower[i])),
                     float(min(theta[i] + 1.96 * sd[i], e.upper[i])), e.units[i],
                     bool(at_bound[i]))
            for i, p in enumerate(e.params)}


@dataclass(frozen=True)
class Fitted:
    """The chosen effects fitted: found effects, the physical link fit, the withheld
    prediction and the resulting bodies."""

    found: list[FoundEffect]
    inert: InertialFit | None
    pred: F64
    bodies: dict[int, BodyChange]


def _contribution(e: Effect, theta: F64) -> F64:
    """The RMS torque effect ``e`` adds on each joint with parameters ``theta`` (n,)."""
    return np.sqrt(np.mean((e.columns @ theta) ** 2, axis=0))


def _with_part_mass(arm: Arm, f: FoundEffect) -> FoundEffect:
    """An absent part's share as the mass missing too (kg, same interval)."""
    if f.name != "absent_part":
        return f
    part = next(a for a in arm.attachments if a.name == f.detail)
    s = f.params["share"]
    mass = Param(s.value * part.mass, s.low * part.mass, s.high * part.mass, "kg", s.at_bound)
    return replace(f, params={**f.params, "mass": mass})


def fit_chosen(arm: Arm, chosen: list[Effect], steps: list[Step], b: F64, sigma: F64,
                opt: DynamicsOptions, guard: int, pred: F64 | None) -> Fitted:
    """Fit ``chosen`` on the whole log (eq. F2; the links physically, eq. P1); ``pred`` the
    withheld prediction when known, else cross-validated here."""
    d = design(chosen, *b.shape)
    fit = solve(d, b, sigma)
    values, inert, named = fit.theta, None, None
    if any(e.name == "inertial" for e in chosen):
        # physical by construction (eq. P1); the withheld error is that of the physical fit
        inert, values, pred, named = _links(arm, chosen, fit.theta, b, sigma, opt, guard)
    elif pred is None:
        pred = cross_validate(d, b, sigma, opt.folds, guard)
    at_bound = np.isclose(values, d.lower) | np.isclose(values, d.upper)
    drop = {st.key: prev.chi2 - st.chi2 for prev, st in itertools.pairwise(steps)}
    found = [FoundEffect(e.key, e.name, e.joint, e.detail,
                         params_of(e, values[sl], fit.cov[sl, sl], at_bound[sl]),
                         drop.get(e.key, 0.0), _contribution(e, values[sl]))
             for e, sl in zip(chosen, d.slices, strict=True)]
    # findings in order of the torque they explain (N m over all joints): a hand of 0.76 kg
    # on the big joints before a wrist's friction that is large only in its own noise units;
    # the model's physics before the sensors' offsets and gains
    found = sorted((_with_part_mass(arm, f) for f in found),
                   key=lambda f: (f.name in ("offset", "gain"),
                                  -float(np.sqrt(np.mean(f.rms_nm**2)))))
    if named is not None and inert is not None:
        return Fitted(found, inert, pred, link_changes(arm, inert.phi, named))
    bodies = resulting_bodies(
        arm, [(f.key, f.name, f.detail, {k: p.value for k, p in f.params.items()})
              for f in found if f.name in BODY_CHANGES], None if inert is None else inert.phi)
    return Fitted(found, inert, pred, bodies)


def _links(arm: Arm, chosen: list[Effect], theta: F64, b: F64, sigma: F64,
           opt: DynamicsOptions, guard: int
           ) -> tuple[InertialFit, F64, F64, dict[int, BodyChange] | None]:
    """The link inertias fitted physically (eq. P1). With a named part or link among the
    chosen effects (an absent hand, a link's mass, a payload), those are applied to the
    model first at their least-squares values and the links are fitted on top, so that the
    physical fit holds the resulting bodies. The fit, every effect's values in ``chosen``
    order, the withheld prediction and the named changes (None without them)."""
    d = design(chosen, *b.shape)
    first = [i for i, e in enumerate(chosen) if e.name in BODY_CHANGES]
    # the named changes at their values without the link inertias (the forty combinations
    # overlap a link's mass: fitted together the pair is not determined)
    simple = [e for e in chosen if e.name != "inertial"]
    ds = design(simple, *b.shape)
    theta = theta.copy()
    theta_s = solve(ds, b, sigma, with_cov=False).theta
    for sl, e in zip(ds.slices, simple, strict=True):
        theta[d.slices[chosen.index(e)]] = theta_s[sl]
    named = resulting_bodies(arm, [(chosen[i].key, chosen[i].name, chosen[i].detail,
                                    dict(zip(chosen[i].params, theta[d.slices[i]],
                                             strict=True))) for i in first])
    if not first or not all(c.physical for c in named.values()):
        inert = physical_fit(arm, chosen, b, sigma)
        pred, _ = physical_cross_validate(arm, chosen, b, sigma, opt.folds, guard)
        return inert, inert.theta, pred, None
    offset = sum(chosen[i].columns @ theta[d.slices[i]] for i in first)
    rest = [e for i, e in enumerate(chosen) if i not in first]
    changed = ChangedArm(arm, {bb: c.phi for bb, c in named.items()})
    inert = physical_fit(changed, rest, b - offset, sigma)
    pred, _ = physical_cross_validate(changed, rest, b - offset, sigma, opt.folds, guard)
    values = theta.copy()
    for sl, e in zip(design(rest, *b.shape).slices, rest, strict=True):
        values[d.slices[chosen.index(e)]] = inert.theta[sl]
    return inert, values, pred + offset, named


def physical_gate(arm: Arm, chosen: list[Effect], steps: list[Step], b: F64, sigma: F64,
                   opt: DynamicsOptions, guard: int, pred: F64
                   ) -> tuple[list[Effect], Fitted, list[str]]:
    """Fit the chosen effects; an effect of the masses that leaves a body non-physical (eq.
    R5) is dropped and the rest refitted, said in the notes: impossible values never reach
    the result."""
    notes: list[str] = []
    fitted = fit_chosen(arm, chosen, steps, b, sigma, opt, guard, pred)
    for _ in range(len(chosen)):
        bad = [c for c in fitted.bodies.values() if not c.physical]
        culprits = [k for c in bad for k in c.effects]
        if not culprits:
            break
        key = _culprit(culprits, [e.key for e in chosen])
        body = next(c for c in bad if key in c.effects)
        notes.append(f"{key} left out: with it link {body.name} would not be physical (mass "
                     f"{body.phi[0]:.3g} kg, or a centre or inertia no body can have)")
        chosen = [e for e in chosen if e.key != key]
        fitted = fit_chosen(arm, chosen, steps, b, sigma, opt, guard, None)
    idle = _idle(fitted.found, sigma)
    if idle:
        notes.append(f"{', '.join(idle)} left out: the final fit leaves it at nothing (under "
                     f"{IDLE:g} of the noise on every joint; other effects took its torques)")
        chosen = [e for e in chosen if e.key not in idle]
        fitted = fit_chosen(arm, chosen, steps, b, sigma, opt, guard, None)
    return chosen, fitted, notes


def _culprit(culprits: list[str], order: list[str]) -> str:
    """The effect that goes: the link inertias first (a named part or link stays, they go),
    else the latest chosen (an effect found early never gives way to a later one)."""
    if "inertial" in culprits:
        return "inertial"
    return max(culprits, key=lambda k: order.index(k) if k in order else -1)


def _idle(found: list[FoundEffect], sigma: F64) -> list[str]:
    """The effects the final fit leaves at nothing (their torques taken by others): no
    findings."""
    return [f.key for f in found if f.rms_nm is not None and np.all(f.rms_nm < IDLE * sigma)]


Gated = tuple[list[Effect], Fitted, list[str]]
