"""Findings far outside any physical arm point at the data, not at the model (issue 41
finding 6, issue 43 "absurd values"). After the diagnosis, :func:`plausibility` checks what it
found against the arm's own scale:

* a link's mass changed by more than :data:`LINK_FACTOR` times its own mass, or by more than
  :data:`TONNE` kg (a link 1.3e5 kg heavier);
* a payload heavier than the whole arm (its moving links' mass);
* Coulomb friction, or the viscous or rotor-inertia torque along the log, beyond
  :data:`TORQUE_FACTOR` times the largest torque the joint measured, or above its torque
  limit (friction the joint could never overcome);
* a torque-sensor gain of more than :data:`GAIN_FACTOR` times, or under 1 / it (the log's
  torques in another unit);
* the named effects raise the withheld error above the nominal model's (a "-7 % removed").

Any of these: the findings are not reported as effects (the diagnosis keeps the nominal
model: no effect, no body change, nothing written to corrected.xml, the withheld error the
nominal's) and :attr:`DynamicDiagnosis.data_problems` says what was absurd and the likely
cause, read from the log: positions that barely move (radians read as degrees, x 1/57.3),
torques far from the model's gravity torques (mN m read as N m, x 1000), a stuck channel
(:mod:`zrp.gap.dynamics.frozen`), a clock whose steps vary more than a controller's.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.results import DynamicDiagnosis

__all__ = ["GAIN_FACTOR", "LINK_FACTOR", "TONNE", "TORQUE_FACTOR", "likely_causes",
           "plausibility"]

LINK_FACTOR = 10.0
TONNE = 1000.0
TORQUE_FACTOR = 2.0
GAIN_FACTOR = 10.0
_SMALL_SPAN = 0.05  # rad: every hinge moving less than this (3 deg) looks like rad read as deg
_UNIT_RATIO = 30.0  # measured / model gravity torque beyond this: another torque unit
_STEP_SPREAD = 20.0


def _arm_mass(arm: Any) -> float:
    return float(sum(max(float(arm.body_params(b)[0]), 0.0) for b in arm.moving_bodies()))


def _bodies(arm: Any, d: DynamicDiagnosis) -> list[str]:
    out = []
    total = _arm_mass(arm)
    for b, c in d.bodies.items():
        dm, m0 = c.mass_change, float(c.phi0[0])
        payload = "payload" in c.effects and b == getattr(arm, "tool_body", None)
        if payload and dm > max(total, 1e-9):
            out.append(f"a payload of {dm:.4g} kg, heavier than the whole arm ({total:.4g} kg)")
        elif not payload and (abs(dm) > TONNE or (m0 > 0.1 and abs(dm) > LINK_FACTOR * m0)):
            out.append(f"link {c.name}'s mass {dm:+.4g} kg (its own {m0:.4g} kg)")
    return out


def _peaks(d: DynamicDiagnosis, log: Any) -> tuple[F64, F64, F64]:
    """Per joint: the largest measured |torque|, |qd| and |qdd| (99th percentiles)."""
    tau = np.percentile(np.abs(np.asarray(log.tau, dtype=float)), 99, axis=0)
    s = d.samples
    if s is None or len(s.t) < 3:
        return tau, np.full(tau.shape, np.inf), np.full(tau.shape, np.inf)
    qd = np.asarray(s.qd, dtype=float)
    qdd = np.gradient(qd, np.asarray(s.t, dtype=float), axis=0)
    return tau, np.percentile(np.abs(qd), 99, axis=0), np.percentile(np.abs(qdd), 99, axis=0)


def _joint_terms(arm: Any, d: DynamicDiagnosis, log: Any) -> list[str]:
    out = []
    tau, qd, qdd = _peaks(d, log)
    limit = np.asarray(arm.torque_limits(), dtype=float) if hasattr(arm, "torque_limits") \
        else np.full(tau.shape, np.inf)
    scale = {"coulomb": lambda k: 1.0, "viscous": lambda k: qd[k],
             "armature": lambda k: qdd[k]}
    for e in d.effects:
        k = e.joint
        if k is None or e.name not in (*scale, "gain") or e.name not in e.params:
            continue
        v = float(e.params[e.name].value)
        if e.name == "gain":
            if 1.0 + v > GAIN_FACTOR or 1.0 + v < 1.0 / GAIN_FACTOR:
                out.append(f"a torque gain of x{1.0 + v:.4g} on joint {k + 1}")
            continue
        torque = abs(v) * float(scale[e.name](k))
        cap = min(TORQUE_FACTOR * float(tau[k]), float(limit[k]))
        if np.isfinite(torque) and torque > max(cap, 1e-9):
            out.append(f"{e.name} {v:.4g} {e.params[e.name].unit} on joint {k + 1} "
                       f"({torque:.4g} N m, beyond the {float(tau[k]):.4g} N m it measured"
                       + (f" and its limit {float(limit[k]):.4g} N m)" if np.isfinite(limit[k])
                          else ")"))
    return out


def _worse(d: DynamicDiagnosis) -> list[str]:
    m = d.measured
    if not d.found or not m.any():
        return []
    before = float(np.sqrt(np.mean(np.asarray(d.rms_before)[m] ** 2)))
    after = float(np.sqrt(np.mean(np.asarray(d.rms_after)[m] ** 2)))
    if after > before:
        return [f"the named effects raise the withheld error {before:.3g} -> {after:.3g} N m "
                f"({1.0 - after / before:+.0%} removed)"]
    return []


def _torque_ratio(arm: Any, log: Any) -> float | None:
    """Median over the joints with gravity torque of RMS(measured) / RMS(model gravity)."""
    q = np.asarray(log.q, dtype=float)
    rows = np.linspace(0, len(q) - 1, min(len(q), 200)).astype(int)
    try:
        g = np.asarray(arm.gravity_torques(q[rows]), dtype=float)
    except (AttributeError, ValueError):
        return None
    tau = np.asarray(log.tau, dtype=float)[rows]
    rg, rt = np.sqrt(np.mean(g**2, 0)), np.sqrt(np.mean(tau**2, 0))
    use = (rg > 1e-3 * max(float(rg.max()), 1e-12)) & np.asarray(log.measured)
    return float(np.median(rt[use] / rg[use])) if use.any() else None


def likely_causes(arm: Any, log: Any) -> list[str]:
    """The data's likely problems, in words (module docstring); empty when none is seen."""
    out = []
    q = np.asarray(log.q, dtype=float)
    rev = np.asarray(arm.revolute(), dtype=bool) if hasattr(arm, "revolute") \
        else np.ones(q.shape[1], bool)
    span = np.ptp(q, axis=0)
    if rev.any() and np.all(span[rev] < _SMALL_SPAN):
        kuka = "KUKA" in log.conditioning.columns
        out.append(f"units of the positions: no hinge moves more than {span[rev].max():.3g} "
                   "rad; radians read as degrees (x 1/57.3)?"
                   + (" The KUKA A1..A7 columns are read in degrees unless declared: write "
                      "A1 [rad] .. in the header" if kuka else " Declare q1 [rad] .."))
    ratio = _torque_ratio(arm, log)
    if ratio is not None and (ratio > _UNIT_RATIO or ratio < 1.0 / _UNIT_RATIO):
        out.append(f"units of the torques: they are {ratio:.3g} x the model's gravity torques"
                   + ("; mN m read as N m (x 1000)? Declare tau1 [mNm] .." if ratio > 1 else
                      "; kN m, or currents without their torque constant?"))
    frozen = [e for e in (*log.conditioning.excluded, *log.unmeasured.values())
              if "frozen" in e]
    out += [f"a stuck channel: {f}" for f in dict.fromkeys(frozen)]
    c = log.conditioning
    if c.step_min_s > 0.0 and c.step_max_s > _STEP_SPREAD * c.step_min_s:
        out.append(f"the clock: steps of {c.step_min_s * 1e3:.3g} to {c.step_max_s * 1e3:.3g} "
                   "ms within segments, more than a controller's jitter (a clock written "
                   "twice, or in another unit?)")
    return out


def plausibility(arm: Any, log: Any, d: DynamicDiagnosis) -> DynamicDiagnosis:
    """``d``, or, when a finding is far outside any physical arm, ``d`` with no findings and
    the data problems said (module docstring)."""
    absurd = [*_bodies(arm, d), *_joint_terms(arm, d, log), *_worse(d)]
    if not absurd:
        return d
    causes = likely_causes(arm, log) or [
        "no single cause seen: check the units of positions (rad, deg) and torques (N m, "
        "mN m), the clock, and channels that hold one value"]
    problems = [f"not physical for this arm: {'; '.join(absurd)}: this points at the data, "
                "not at the model; no effect is reported and corrected.xml is the nominal "
                "model", *(f"likely cause: {c}" for c in causes)]
    return replace(d, effects=[], bodies={}, inertial_fit=None, inertial_phi={},
                   rms_after=np.asarray(d.rms_before, dtype=float).copy(),
                   data_problems=problems)
