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

from dataclasses import replace

import numpy as np

from zrp.arrays import F64
from zrp.blas import blas_threads
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.effects import (
    JOINT_EFFECTS,
    MOTOR_EFFECTS,
    Effect,
    candidate_effects,
    payload_columns,
)
from zrp.gap.dynamics.final import Setup, baseline_fit, not_worse, small_effects
from zrp.gap.dynamics.gate import BODY_CHANGES, Fitted, physical_gate
from zrp.gap.dynamics.localpoly import local_fit
from zrp.gap.dynamics.options import DynamicsOptions
from zrp.gap.dynamics.physical import InertialFit
from zrp.gap.dynamics.plausible import plausibility
from zrp.gap.dynamics.regimes import regime_masks, regime_rms
from zrp.gap.dynamics.results import DynamicDiagnosis, FoundEffect, Samples
from zrp.gap.dynamics.select import forward_select
from zrp.gap.dynamics.states import States, derive_states

__all__ = ["EFFECT_NAMES", "DynamicDiagnosis", "DynamicsOptions", "FoundEffect", "decimated_states",
           "diagnose_dynamics", "model_torques", "torque_noise"]

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
    if opt.window_s is None:
        raise InputError("window_s: give the filter window (a diagnosis's own: "
                         "DynamicDiagnosis.window_s), or let diagnose_dynamics choose it")
    states = derive_states(log, opt.window_s)
    stride = max(1, round(1.0 / (opt.fit_rate_hz * log.dt)))
    return states.every(stride), stride


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


def _setup(arm: Arm, log: TorqueLog, opt: DynamicsOptions) -> Setup:
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
    return Setup(s, stride, b, b_raw, noise, np.where(m, noise, 1.0), effects)


def _notes(arm: Arm, log: TorqueLog, su: Setup, fitted: Fitted, gate: list[str]
           ) -> list[str]:
    notes = [*getattr(arm, "notes", ()),
             f"accelerations by Savitzky-Golay, window {su.s.window_s:.3g} s; fit at "
             f"{1.0 / (su.stride * log.dt):.4g} Hz", *log.conditioning.describe(),
             *(f"left out (shorter than the filter window): {d}" for d in su.s.dropped),
             *gate, *_common_gain(fitted.found)]
    if fitted.inert is not None:
        notes += [fitted.inert.describe(), *_unphysical_links(arm, fitted.inert)]
    return notes


#: The derivative filter windows tried when none is given, s: each a zero-phase low-pass of
#: positions and torques in parallel, about 25, 12 and 6 Hz at its -3 dB point (cubic
#: Savitzky-Golay, :mod:`zrp.gap.dynamics.states`).
WINDOWS = (0.05, 0.1, 0.2)

#: Among windows within this share of the best score, the first in :data:`PREFERRED` is
#: taken (the 0.1 s window, then the shorter one).
WINDOW_TIE = 0.02
PREFERRED = (0.1, 0.05, 0.2)


def _guard(opt: DynamicsOptions) -> int:
    return max(1, round(0.5 * float(opt.window_s or 0.1) * opt.fit_rate_hz))


def choose_window(arm: Arm, log: TorqueLog, opt: DynamicsOptions) -> tuple[float, str]:
    """The derivative filter's window from the data (issue 43): each of :data:`WINDOWS`
    that the log can carry (7 samples and more, within its longest segment) scored by the
    standard identification's withheld error on the raw torques, every joint in units of
    one noise estimate (the middle window's), so that the windows are compared on the same
    scale; within :data:`WINDOW_TIE` of the best, the first of :data:`PREFERRED`. The window
    and a note."""
    longest = max(b - a for a, b in log.segment_ranges)
    fits = [w for w in WINDOWS if 7 <= round(w / log.dt) <= longest]
    if not fits:
        return 0.1, "derivative filter window 0.1 s (the log is too short or coarse to choose)"
    ref = np.where(log.measured, torque_noise(log, fits[len(fits) // 2]), 1.0)
    scores = {}
    for w in fits:
        o = replace(opt, window_s=w)
        su = _setup(arm, log, o)
        _, pred = baseline_fit(arm, su, o, _guard(o))
        scores[w] = float(np.mean(((su.b_raw - pred) / ref) ** 2))
    best = min(scores.values())
    w = next(x for x in PREFERRED if scores.get(x, np.inf) <= best * (1.0 + WINDOW_TIE))
    said = ", ".join(f"{x:g} s: {c:.3g}" for x, c in scores.items())
    return w, (f"derivative filter window {w:g} s, chosen from the data: the standard "
               f"identification's withheld chi2 (one noise scale) {said}")


#: A joint whose model torque varies by more than UNUSABLE_NOISE times its noise while its
#: effort follows it with a correlation under UNUSABLE_CORR, and of whose effort the standard
#: identification explains less than UNUSABLE_SHARE on the withheld segments, is not
#: carrying a torque.
UNUSABLE_NOISE = 3.0
UNUSABLE_CORR = 0.3
UNUSABLE_SHARE = 0.2


def _why_unusable(tau: F64, tau0: F64, left: F64, noise: float) -> str | None:
    """Why a joint's effort ``tau`` is no torque (None: it is one): ``tau0`` the model's
    torque, ``left`` what the standard identification leaves of it (withheld)."""
    spread, var = float(np.std(tau0)), float(np.var(tau))
    if spread <= UNUSABLE_NOISE * noise or var == 0.0:
        return None
    r = float(np.corrcoef(tau, tau0)[0, 1])
    if r >= UNUSABLE_CORR or 1.0 - float(np.mean(left**2)) / var > UNUSABLE_SHARE:
        return None
    head = (f"its effort does not behave like a torque: the model's torque there varies by "
            f"{spread:.3g} N m RMS ({spread / noise:.1f}x the noise) and the effort follows it "
            f"with a correlation of {r:+.2f}")
    if r <= -UNUSABLE_CORR:
        return head + ("; it runs the other way: a torque constant or transmission sign "
                       "reversed on this joint?")
    return head + ("; and the standard identification explains none of it: check what this "
                   "channel logs (a current of another drive, a position error)")


def unusable_efforts(arm: Arm, log: TorqueLog, opt: DynamicsOptions) -> TorqueLog:
    """``log`` with the joints whose effort does not behave like a torque left out (issue
    44): the model's torque varies far above the noise there and the logged effort does not
    follow it (a torso's lift whose effort is a position error, a channel that logs something
    else, a reversed sign). Such a joint is named in :attr:`TorqueLog.unmeasured`, not
    fitted; with every joint so, nothing is left out (the diagnosis says what it finds)."""
    su = _setup(arm, log, opt)
    _, pred = baseline_fit(arm, su, opt, _guard(opt))
    tau, left = su.s.tau_raw, su.b_raw - pred
    bad = {int(k): why for k in np.flatnonzero(log.measured)
           if (why := _why_unusable(tau[:, k], tau[:, k] - su.b_raw[:, k], left[:, k],
                                    float(su.noise[k])))}
    if not bad or len(bad) == int(np.sum(log.measured)):
        return log
    return replace(log, unmeasured={**log.unmeasured, **bad})


def _diagnose(arm: Arm, log: TorqueLog, options: DynamicsOptions | None) -> DynamicDiagnosis:
    opt = options or DynamicsOptions()
    _check_inputs(arm, log)
    said = f"derivative filter window {opt.window_s:g} s (given)" if opt.window_s else ""
    if opt.window_s is None:
        window, said = choose_window(arm, log, opt)
        opt = replace(opt, window_s=window)
    log = unusable_efforts(arm, log, opt)
    su = _setup(arm, log, opt)
    s, b, b_raw, sigma = su.s, su.b, su.b_raw, su.sigma
    guard = _guard(opt)
    chosen, steps, pred = forward_select(su.effects, b, b_raw, sigma, folds=opt.folds,
                                         guard=guard, min_rel=opt.min_rel, min_abs=opt.min_abs,
                                         max_effects=opt.max_effects or 3 * arm.n + 4)
    chosen, fitted, gate_notes = physical_gate(arm, chosen, steps, b, sigma, opt, guard, pred)
    base, chosen, fitted, gate_notes = not_worse(arm, su, opt, guard, steps,
                                                  (chosen, fitted, gate_notes))
    fitted = replace(fitted, found=small_effects(chosen, fitted.found, su, opt, guard))
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
        inert, {} if inert is None else inert.phi,
        [said, *_notes(arm, log, su, fitted, gate_notes)],
        Samples(s.t, s.q, s.qd, b_raw, b_raw - pred), bodies, dict(log.unmeasured), base,
        s.window_s, {k: tuple(float(x) for x in g) for k, g in (
            log.transmission.coupled_motors() if log.transmission else [])})
