"""The dynamic gap diagnosis (:func:`diagnose_dynamics`): along a torque log, where the MuJoCo
model's inverse-dynamics torques miss the measured ones, which effect causes it, its size
with an interval, and how far the withheld torque error shrinks.

Steps:

1. states: q, qd, qdd and the torques by the zero-phase Savitzky-Golay filter
   (:func:`zrp.gap.dynamics.derive_states`), then taken at ``fit_rate_hz``;
2. the model's torques tau0 = ``mj_inverse`` along the states (eq. R2), plus the logged
   payload (the log's ``payload`` column, a point mass at the tool point) when there is one:
   a payload found is then what the log does not declare;
3. the torque noise sigma_k of each joint (eq. N1): the RMS of the raw torque minus its
   Savitzky-Golay smoothing, divided by sqrt(1 - h0) (h0: the smoother's centre weight; the
   smoothing removes the noise, not the trajectory's torques, which lie far below its cut-off);
   this is the floor no model can go below;
4. candidate effects (:mod:`zrp.gap.dynamics.effects`) chosen by forward selection on the
   out-of-segment chi^2 (:mod:`zrp.gap.dynamics.select`, eq. S1);
5. the chosen effects refitted on the whole log with physical bounds and 95 % intervals
   (:mod:`zrp.gap.dynamics.fit`, eq. F2); link inertial parameters, when chosen, fitted
   physically consistent by construction (log-Cholesky, :mod:`zrp.gap.dynamics.physical`,
   eq. P1) jointly with the other effects, and the withheld error is that of this fit;
6. "cannot tell": a joint effect whose regressor column is (almost) a multiple of another's
   on the same joint along this log (e.g. Coulomb friction and a torque offset when the joint
   never reverses), or (almost) zero (the joint never moves or accelerates).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from zrp.arrays import F64
from zrp.blas import blas_threads
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.baseline import standard_effects
from zrp.gap.dynamics.cvgram import CVGram
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.effects import (
    JOINT_EFFECTS,
    MOTOR_EFFECTS,
    Effect,
    candidate_effects,
    inertial_correction,
    payload_columns,
)
from zrp.gap.dynamics.fit import cross_validate, design, solve
from zrp.gap.dynamics.localpoly import local_fit
from zrp.gap.dynamics.physical import InertialFit, physical_cross_validate, physical_fit
from zrp.gap.dynamics.plausible import plausibility
from zrp.gap.dynamics.regimes import regime_masks, regime_rms
from zrp.gap.dynamics.resulting import BodyChange, ChangedArm, link_changes, resulting_bodies
from zrp.gap.dynamics.results import Baseline, DynamicDiagnosis, FoundEffect, Param, Samples
from zrp.gap.dynamics.select import KEPT, Step, chi2_of, forward_select
from zrp.gap.dynamics.states import States, derive_states

__all__ = ["EFFECT_NAMES", "DynamicDiagnosis", "DynamicsOptions", "FoundEffect", "decimated_states",
           "diagnose_dynamics", "model_torques", "torque_noise"]

#: An effect whose torques stay under this share of the noise on every joint in the final fit
#: is left out (another effect took them).
IDLE = 0.05

#: The effects that change a body of the model (their resulting bodies must be physical).
BODY_CHANGES = ("payload", "absent_part", "link_mass")


@dataclass(frozen=True)
class DynamicsOptions:
    """How the diagnosis runs (see the module docstring)."""

    window_s: float = 0.1
    fit_rate_hz: float = 100.0
    folds: int = 5
    min_rel: float = 0.03
    min_abs: float = 0.05
    max_effects: int | None = None  # None: 3 a joint and 4 more (friction on every joint
    # takes up to three effects there, Coulomb, viscous and Stribeck)
    inertial: bool = True
    collinear: float = 0.1
    effects: tuple[str, ...] | None = None  # the effect names tried (None: all)


def torque_noise(log: TorqueLog, window_s: float, polyorder: int = 3) -> F64:
    """sigma_k of each joint's raw torque (eq. N1), segment by segment on the real time axis
    (never across a gap; the segments' ends left out when long enough)."""
    w = max(round(window_s / log.dt) | 1, polyorder + 2 | 1)
    parts = []
    for a, b in log.segment_ranges:
        ww = min(w, (b - a) - (1 - (b - a) % 2))
        if ww <= polyorder:
            continue
        (smooth,), h0 = local_fit(log.t[a:b], log.tau[a:b], ww, polyorder)
        r = (log.tau[a:b] - smooth) / np.sqrt(1.0 - h0)[:, None]
        parts.append(r[ww:-ww] if b - a > 3 * ww else r)
    if not parts:
        raise InputError(f"{log.source}: no segment long enough to estimate the torque noise")
    r = np.concatenate(parts)
    return np.maximum(np.sqrt(np.mean(r * r, axis=0)), 1e-9)


def decimated_states(log: TorqueLog, opt: DynamicsOptions) -> tuple[States, int]:
    """The states at the fit rate and the stride taken (step 1 of the module docstring)."""
    return _decimated(log, opt)


def model_torques(arm: Arm, log: TorqueLog, s: States, stride: int) -> F64:
    """The model's torques along the states (step 2): inverse dynamics plus the logged
    payload, a point mass at the tool point (the log declares it: it is part of the
    model)."""
    tau0 = arm.inverse_dynamics(s.q, s.qd, s.qdd)
    if log.payload is not None and np.any(log.payload > 0.0):
        known = log.payload[s.index][:, None]
        tau0 = tau0 + payload_columns(arm, s.q, s.qd, s.qdd)[..., 0] * known
    return tau0


def _decimated(log: TorqueLog, opt: DynamicsOptions) -> tuple[States, int]:
    states = derive_states(log, opt.window_s)
    stride = max(1, round(1.0 / (opt.fit_rate_hz * log.dt)))
    return states.every(stride), stride


def _params(e: Effect, theta: F64, cov: F64, at_bound: np.ndarray) -> dict[str, Param]:
    """The fitted parameters with 95 % intervals, each held inside its domain (an interval
    never reaches values the parameter cannot have)."""
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {p: Param(float(theta[i]), float(max(theta[i] - 1.96 * sd[i], e.lower[i])),
                     float(min(theta[i] + 1.96 * sd[i], e.upper[i])), e.units[i],
                     bool(at_bound[i]))
            for i, p in enumerate(e.params)}


def _collinear(k: int, cols: dict[str, F64], limit: float) -> list[str]:
    out: list[str] = []
    for name, y in cols.items():
        norm = float(np.linalg.norm(y))
        if norm < 1e-9 * np.sqrt(y.size):
            out.append(f"joint {k + 1}: {name} (the log does not excite it)")
            continue
        for other, z in cols.items():
            zz = float(z @ z)
            if other <= name or zz == 0.0:
                continue
            perp = y - z * (y @ z) / zz
            if np.linalg.norm(perp) < limit * norm:
                out.append(f"joint {k + 1}: {name} from {other} (their torques are "
                           "proportional along this log)")
    return out


def _cannot_tell(effects: list[Effect], sigma: F64, limit: float) -> list[str]:
    """Joint effects (Stribeck aside) that this log cannot separate or does not excite."""
    by_joint: dict[int, dict[str, F64]] = {}
    for e in effects:
        if e.joint is not None and not e.detail:
            by_joint.setdefault(e.joint, {})[e.name] = e.columns[:, e.joint, 0] / sigma[e.joint]
    out: list[str] = []
    for k, cols in sorted(by_joint.items()):
        out += _collinear(k, cols, limit)
    return out


#: Every effect name the diagnosis can try.
EFFECT_NAMES = (*JOINT_EFFECTS, *MOTOR_EFFECTS, "payload", *BODY_CHANGES[1:], "inertial")


def _known_effects(names: tuple[str, ...]) -> tuple[str, ...]:
    bad = sorted(set(names) - set(EFFECT_NAMES))
    if bad:
        raise InputError(f"effects: unknown effect(s) {', '.join(bad)}; known: "
                         f"{', '.join(EFFECT_NAMES)}")
    return names


def _check_inputs(arm: Arm, log: TorqueLog) -> None:
    if log.n_joints != arm.n:
        raise InputError(f"{log.source}: {log.n_joints} joints (q1..q{log.n_joints}), but the "
                         f"model {arm.name!r} has {arm.n}")


def diagnose_dynamics(arm: Arm, log: TorqueLog, options: DynamicsOptions | None = None
                      ) -> DynamicDiagnosis:
    """Diagnose the dynamic gap of ``arm`` along ``log`` (module docstring); one BLAS thread
    (many small products: see :mod:`zrp.blas`)."""
    with blas_threads(1):
        return plausibility(arm, log, _diagnose(arm, log, options))  # issue 41: data problems


@dataclass(frozen=True)
class _Fitted:
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


def _fit_chosen(arm: Arm, chosen: list[Effect], steps: list[Step], b: F64, sigma: F64,
                opt: DynamicsOptions, guard: int, pred: F64 | None) -> _Fitted:
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
                         _params(e, values[sl], fit.cov[sl, sl], at_bound[sl]),
                         drop.get(e.key, 0.0), _contribution(e, values[sl]))
             for e, sl in zip(chosen, d.slices, strict=True)]
    # findings in order of the torque they explain (N m over all joints): a hand of 0.76 kg
    # on the big joints before a wrist's friction that is large only in its own noise units;
    # the model's physics before the sensors' offsets and gains
    found = sorted((_with_part_mass(arm, f) for f in found),
                   key=lambda f: (f.name in ("offset", "gain"),
                                  -float(np.sqrt(np.mean(f.rms_nm**2)))))
    if named is not None and inert is not None:
        return _Fitted(found, inert, pred, link_changes(arm, inert.phi, named))
    bodies = resulting_bodies(
        arm, [(f.key, f.name, f.detail, {k: p.value for k, p in f.params.items()})
              for f in found if f.name in BODY_CHANGES], None if inert is None else inert.phi)
    return _Fitted(found, inert, pred, bodies)


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


def _physical_gate(arm: Arm, chosen: list[Effect], steps: list[Step], b: F64, sigma: F64,
                   opt: DynamicsOptions, guard: int, pred: F64
                   ) -> tuple[list[Effect], _Fitted, list[str]]:
    """Fit the chosen effects; an effect of the masses that leaves a body non-physical (eq.
    R5) is dropped and the rest refitted, said in the notes: impossible values never reach
    the result."""
    notes: list[str] = []
    fitted = _fit_chosen(arm, chosen, steps, b, sigma, opt, guard, pred)
    for _ in range(len(chosen)):
        bad = [c for c in fitted.bodies.values() if not c.physical]
        culprits = [k for c in bad for k in c.effects]
        if not culprits:
            break
        # the link inertias are the last resort: a named part or link stays, they go
        order = [e.key for e in chosen]
        key = "inertial" if "inertial" in culprits else max(
            culprits, key=lambda k: order.index(k) if k in order else -1)
        body = next(c for c in bad if key in c.effects)
        notes.append(f"{key} left out: with it link {body.name} would not be physical (mass "
                     f"{body.phi[0]:.3g} kg, or a centre or inertia no body can have)")
        chosen = [e for e in chosen if e.key != key]
        fitted = _fit_chosen(arm, chosen, steps, b, sigma, opt, guard, None)
    idle = _idle(fitted.found, sigma)
    if idle:
        notes.append(f"{', '.join(idle)} left out: the final fit leaves it at nothing (under "
                     f"{IDLE:g} of the noise on every joint; other effects took its torques)")
        chosen = [e for e in chosen if e.key not in idle]
        fitted = _fit_chosen(arm, chosen, steps, b, sigma, opt, guard, None)
    return chosen, fitted, notes


_Gated = tuple[list[Effect], "_Fitted", list[str]]


def _baseline(arm: Arm, su: _Setup, opt: DynamicsOptions, guard: int
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


def _not_worse(arm: Arm, su: _Setup, opt: DynamicsOptions, guard: int, steps: list[Step],
               selected: _Gated) -> tuple[Baseline, list[Effect], _Fitted, list[str]]:
    """The final model never worse on the withheld segments than the standard
    identification (eq. B0), in noise units (chi2) and in N m over the joints (what the
    report gives): when the selected effects lose to it clearly (by the selection's own
    threshold, ``min_rel``), they are completed with its terms, said in the notes."""
    base, base_pred = _baseline(arm, su, opt, guard)
    chosen, fitted, notes = selected
    score, ref = _scores(su, fitted.pred), _scores(su, base_pred)
    if all(r >= x * (1.0 - opt.min_rel) for r, x in zip(ref, score, strict=True)):
        return base, chosen, fitted, notes
    taken = {(e.name, e.joint) for e in chosen}
    more = [e for e in standard_effects(su.effects) if (e.name, e.joint) not in taken]
    union = _physical_gate(arm, chosen + more, steps, su.b, su.sigma, opt, guard, None)
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


def _scores(su: _Setup, pred: F64) -> tuple[float, float]:
    """The withheld chi2 and the withheld RMS over the joints (N m) of a prediction (a
    joint whose torque is not data has no residual: it counts as zero in both)."""
    r = su.b_raw - pred
    return chi2_of(su.b_raw, pred, su.sigma), float(np.sqrt(np.mean(r * r)))


def _small(chosen: list[Effect], found: list[FoundEffect], su: _Setup, opt: DynamicsOptions,
           guard: int) -> list[FoundEffect]:
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


def _idle(found: list[FoundEffect], sigma: F64) -> list[str]:
    """The effects the final fit leaves at nothing (their torques taken by others): no
    findings."""
    return [f.key for f in found if f.rms_nm is not None and np.all(f.rms_nm < IDLE * sigma)]


def _common_gain(found: list[FoundEffect]) -> list[str]:
    """Gains of one sign on several joints: a symptom to explain, not a sensor finding."""
    gains = [e for e in found if e.name == "gain"]
    signs = {np.sign(e.params["gain"].value) for e in gains}
    if len(gains) < 2 or len(signs) != 1:
        return []
    vals = [e.params["gain"].value for e in gains]
    joints = ", ".join(str(e.joint + 1) for e in gains if e.joint is not None)
    return [f"torque gains of {min(vals):+.0%} .. {max(vals):+.0%} on joints {joints}: a gain "
            "common to several joints is a symptom, not a sensor finding: a mass the model has "
            "and the arm lacks (a hand, a tool), or the reverse, or one torque constant wrong "
            "on every motor. Check the model's masses and the torque constants before "
            "calibrating the sensors"]


def _unphysical_links(arm: Arm, inert: InertialFit) -> list[str]:
    """Where the physical link fit cannot follow the data (farther from the unconstrained fit
    than the noise explains): each link whose unconstrained fit is not a body, and what it
    would need."""
    out: list[str] = []
    if inert.matched:
        return out
    for b in inert.unphysical_links():
        ph, ph0 = inert.unconstrained_phi[b], arm.body_params(b)
        out.append(f"link {arm.body_name(b)}: the unconstrained fit needs mass "
                   f"{ph[0]:.3g} kg (model {ph0[0]:.3g} kg) with a centre or inertia no body "
                   "can have (pseudo-inertia not positive definite); the physical fit keeps it "
                   "a body. Check the model there: a part missing or misplaced on it (a hand, a "
                   "cable carrier, a counterweight) asks for such a link")
    return out


def _measured_only(e: Effect, measured: np.ndarray) -> Effect:
    """``e`` with no torque on the joints whose torque is not data."""
    cols = e.columns.copy()
    cols[:, ~measured, :] = 0.0
    full = None if e.full is None else e.full * measured[None, :, None]
    return replace(e, columns=cols, full=full)


@dataclass(frozen=True)
class _Setup:
    """Steps 1-3 and the candidates: the states, the residual torques (filtered and raw),
    the noise estimate and the weights of the fit (1 on a joint that is not data)."""

    s: States
    stride: int
    b: F64
    b_raw: F64
    noise: F64
    sigma: F64
    effects: list[Effect]


def _setup(arm: Arm, log: TorqueLog, opt: DynamicsOptions) -> _Setup:
    # a joint whose torque is not data (constant, zero) is left out: no residual, no column
    if not np.any(log.measured):
        raise InputError(f"{log.source}: no joint's torque is data ("
                         + "; ".join(f"joint {k + 1}: {w}" for k, w in log.unmeasured.items())
                         + ")")
    noise = torque_noise(log, opt.window_s)
    s, stride = _decimated(log, opt)
    tau0 = model_torques(arm, log, s, stride)
    b, b_raw = s.tau - tau0, s.tau_raw - tau0
    effects = candidate_effects(arm, s.q, s.qd, s.qdd, tau0, inertial=opt.inertial,
                                transmission=log.transmission)
    m = log.measured
    if not np.all(m):
        b[:, ~m] = 0.0
        b_raw[:, ~m] = 0.0
        effects = [_measured_only(e, m) for e in effects if e.joint is None or m[e.joint]]
    if opt.effects is not None:
        effects = [e for e in effects if e.name in _known_effects(opt.effects)]
    return _Setup(s, stride, b, b_raw, noise, np.where(m, noise, 1.0), effects)


def _notes(arm: Arm, log: TorqueLog, su: _Setup, fitted: _Fitted, gate: list[str]
           ) -> list[str]:
    notes = [*getattr(arm, "notes", ()),
             f"accelerations by Savitzky-Golay, window {su.s.window_s:.3g} s; fit at "
             f"{1.0 / (su.stride * log.dt):.4g} Hz", *log.conditioning.describe(),
             *(f"left out (shorter than the filter window): {d}" for d in su.s.dropped),
             *gate, *_common_gain(fitted.found)]
    if fitted.inert is not None:
        notes += [fitted.inert.describe(), *_unphysical_links(arm, fitted.inert)]
    return notes


def _diagnose(arm: Arm, log: TorqueLog, options: DynamicsOptions | None) -> DynamicDiagnosis:
    opt = options or DynamicsOptions()
    _check_inputs(arm, log)
    su = _setup(arm, log, opt)
    s, b, b_raw, sigma = su.s, su.b, su.b_raw, su.sigma
    guard = max(1, round(0.5 * opt.window_s * opt.fit_rate_hz))
    chosen, steps, pred = forward_select(su.effects, b, b_raw, sigma, folds=opt.folds,
                                         guard=guard, min_rel=opt.min_rel, min_abs=opt.min_abs,
                                         max_effects=opt.max_effects or 3 * arm.n + 4)
    chosen, fitted, gate_notes = _physical_gate(arm, chosen, steps, b, sigma, opt, guard, pred)
    base, chosen, fitted, gate_notes = _not_worse(arm, su, opt, guard, steps,
                                                  (chosen, fitted, gate_notes))
    fitted = replace(fitted, found=_small(chosen, fitted.found, su, opt, guard))
    masks = regime_masks(s.qd, arm.gravity_torques(s.q), guard)
    ties = [f"{st.key} from {', '.join(st.ties)} (each explains the withheld torques to within "
            "10 % of the other; the simpler is named)" for st in steps[1:] if st.ties]
    inert, pred = fitted.inert, fitted.pred
    bodies = {b: replace(c, torque_rms=np.sqrt(np.mean(
        (arm.regressor(s.q, s.qd, s.qdd, [b])[0] @ (c.phi - c.phi0)) ** 2, axis=0)))
        for b, c in fitted.bodies.items()}
    return DynamicDiagnosis(
        arm.name, arm.joint_names, su.noise, np.sqrt(np.mean(b_raw**2, 0)),
        np.sqrt(np.mean((b_raw - pred) ** 2, 0)), steps, fitted.found,
        ties + _cannot_tell([e for e in su.effects if e.name in JOINT_EFFECTS], sigma,
                            opt.collinear),
        {"before": regime_rms(b_raw, masks), "after": regime_rms(b_raw - pred, masks)},
        inert, {} if inert is None else inert.phi, _notes(arm, log, su, fitted, gate_notes),
        Samples(s.t, s.q, s.qd, b_raw, b_raw - pred), bodies, dict(log.unmeasured), base,
        s.window_s)
