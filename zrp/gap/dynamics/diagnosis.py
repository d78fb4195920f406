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

from dataclasses import dataclass, field

import numpy as np

from zrp.arrays import F64
from zrp.blas import blas_threads
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.effects import JOINT_EFFECTS, Effect, candidate_effects, payload_columns
from zrp.gap.dynamics.fit import design, solve
from zrp.gap.dynamics.localpoly import local_fit
from zrp.gap.dynamics.physical import InertialFit, physical_cross_validate, physical_fit
from zrp.gap.dynamics.regimes import regime_masks, regime_rms
from zrp.gap.dynamics.select import Step, forward_select
from zrp.gap.dynamics.states import States, derive_states

__all__ = ["DynamicDiagnosis", "DynamicsOptions", "FoundEffect", "diagnose_dynamics"]


@dataclass(frozen=True)
class DynamicsOptions:
    """How the diagnosis runs (see the module docstring)."""

    window_s: float = 0.1
    fit_rate_hz: float = 100.0
    folds: int = 5
    min_rel: float = 0.03
    min_abs: float = 0.05
    max_effects: int = 8
    inertial: bool = True
    collinear: float = 0.1


@dataclass(frozen=True)
class Param:
    """A fitted parameter: value, 95 % interval, unit, and whether it sits on its bound."""

    value: float
    low: float
    high: float
    unit: str
    at_bound: bool = False


@dataclass(frozen=True)
class FoundEffect:
    """A chosen effect: its key, name, joint (0-based or None), detail, parameters and the
    withheld chi2 drop it brought."""

    key: str
    name: str
    joint: int | None
    detail: str
    params: dict[str, Param]
    chi2_drop: float

    @property
    def label(self) -> str:
        where = "arm" if self.joint is None else f"joint {self.joint + 1}"
        return f"{self.name} ({where}{', ' + self.detail if self.detail else ''})"


@dataclass(frozen=True)
class Samples:
    """The states and residuals at the fit rate, for plots: q, qd, and measured (raw) minus
    model torques before and after (withheld), each (S, n)."""

    t: F64
    q: F64
    qd: F64
    before: F64
    after: F64


@dataclass(frozen=True)
class DynamicDiagnosis:
    """The result (all torques in N m, per joint arrays of shape (n,)).

    Attributes:
        arm, joints: names.
        noise_nm: the torque noise floor sigma_k (eq. N1).
        rms_before: RMS of measured minus model torques (raw torques).
        rms_after: RMS of measured minus corrected torques, each time segment predicted by
            the fit on the others (withheld).
        steps: the forward selection (nominal first) with the withheld chi2 after each.
        effects: the chosen effects, in order of choice.
        cannot_tell: what this log cannot separate, in words.
        regimes: {"before"|"after": {regime: [rms or None per joint]}}.
        inertial_fit: the physically consistent link inertia fit (None: no inertial effect
            chosen), with how far it is from the unconstrained one
            (:class:`zrp.gap.dynamics.physical.InertialFit`).
        inertial_phi: phi_b (eq. R1) of each moving body after it.
        notes: what else the user should know.
    """

    arm: str
    joints: list[str]
    noise_nm: F64
    rms_before: F64
    rms_after: F64
    steps: list[Step]
    effects: list[FoundEffect]
    cannot_tell: list[str]
    regimes: dict[str, dict[str, list[float | None]]]
    inertial_fit: InertialFit | None = None
    inertial_phi: dict[int, F64] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    samples: Samples | None = None

    def effect(self, name: str, joint: int | None = None) -> FoundEffect | None:
        for e in self.effects:
            if e.name == name and e.joint == joint:
                return e
        return None


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


def _decimated(log: TorqueLog, opt: DynamicsOptions) -> tuple[States, int]:
    states = derive_states(log, opt.window_s)
    stride = max(1, round(1.0 / (opt.fit_rate_hz * log.dt)))
    return states.every(stride), stride


def _params(e: Effect, theta: F64, cov: F64, at_bound: np.ndarray) -> dict[str, Param]:
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {p: Param(float(theta[i]), float(theta[i] - 1.96 * sd[i]),
                     float(theta[i] + 1.96 * sd[i]), e.units[i], bool(at_bound[i]))
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


def _check_inputs(arm: Arm, log: TorqueLog) -> None:
    if log.n_joints != arm.n:
        raise InputError(f"{log.source}: {log.n_joints} joints (q1..q{log.n_joints}), but the "
                         f"model {arm.name!r} has {arm.n}")


def diagnose_dynamics(arm: Arm, log: TorqueLog, options: DynamicsOptions | None = None
                      ) -> DynamicDiagnosis:
    """Diagnose the dynamic gap of ``arm`` along ``log`` (module docstring); one BLAS thread
    (many small products: see :mod:`zrp.blas`)."""
    with blas_threads(1):
        return _diagnose(arm, log, options)


def _diagnose(arm: Arm, log: TorqueLog, options: DynamicsOptions | None) -> DynamicDiagnosis:
    opt = options or DynamicsOptions()
    _check_inputs(arm, log)
    sigma = torque_noise(log, opt.window_s)
    s, stride = _decimated(log, opt)
    tau0 = arm.inverse_dynamics(s.q, s.qd, s.qdd)
    if log.payload is not None and np.any(log.payload > 0.0):
        # the logged (known) payload is part of the model: a point mass at the tool point
        known = log.payload[s.index][:, None]
        tau0 = tau0 + payload_columns(arm, s.q, s.qd, s.qdd)[..., 0] * known
    b, b_raw = s.tau - tau0, s.tau_raw - tau0
    effects = candidate_effects(arm, s.q, s.qd, s.qdd, tau0, inertial=opt.inertial)
    guard = max(1, round(0.5 * opt.window_s * opt.fit_rate_hz))
    chosen, steps, pred = forward_select(effects, b, b_raw, sigma, folds=opt.folds, guard=guard,
                                         min_rel=opt.min_rel, min_abs=opt.min_abs,
                                         max_effects=opt.max_effects)
    d = design(chosen, *b.shape)
    fit = solve(d, b, sigma)
    values, inert = fit.theta, None
    if any(e.name == "inertial" for e in chosen):
        # physical by construction (eq. P1); the withheld error is that of the physical fit
        inert = physical_fit(arm, chosen, b, sigma)
        values = inert.theta
        pred, _ = physical_cross_validate(arm, chosen, b, sigma, opt.folds, guard)
    at_bound = np.isclose(values, d.lower) | np.isclose(values, d.upper)
    found = [FoundEffect(e.key, e.name, e.joint, e.detail,
                         _params(e, values[sl], fit.cov[sl, sl], at_bound[sl]),
                         steps[i].chi2 - steps[i + 1].chi2)
             for i, (e, sl) in enumerate(zip(chosen, d.slices, strict=True))]
    masks = regime_masks(s.qd, arm.gravity_torques(s.q), guard)
    notes = [f"accelerations by Savitzky-Golay, window {s.window_s:.3g} s; fit at "
             f"{1.0 / (stride * log.dt):.4g} Hz", *log.conditioning.describe(),
             *(f"left out (shorter than the filter window): {d}" for d in s.dropped)]
    ties = [f"{st.key} from {', '.join(st.ties)} (each explains the withheld torques to within "
            "10 % of the other; the simpler is named)" for st in steps[1:] if st.ties]
    if inert is not None:
        notes.append(inert.describe())
    return DynamicDiagnosis(
        arm.name, arm.joint_names, sigma, np.sqrt(np.mean(b_raw**2, 0)),
        np.sqrt(np.mean((b_raw - pred) ** 2, 0)), steps, found,
        ties + _cannot_tell([e for e in effects if e.name in JOINT_EFFECTS], sigma,
                            opt.collinear),
        {"before": regime_rms(b_raw, masks), "after": regime_rms(b_raw - pred, masks)},
        inert, {} if inert is None else inert.phi, notes,
        Samples(s.t, s.q, s.qd, b_raw, b_raw - pred))
