"""The dynamic gap's verdict in words, a function of the result: a headline (the overall
withheld torque error before -> after, the largest absolute misses, what was found, what
remains), then one line per finding.

The overall error is the RMS over all joints and samples, in N m (joints weighted alike), so
that the joints that miss by the most newton metres lead, not those that miss by the most
multiples of a small noise.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis, FoundEffect
from zrp.gap.dynamics.validation import Validation

__all__ = ["effect_words", "headline", "overall_rms", "validation_words"]

#: A joint whose withheld error is above this multiple of its noise is named under "remains".
REMAINS = 1.5

_JOINT_WORDS = {"coulomb": "Coulomb friction", "viscous": "viscous friction",
                "stribeck": "a Stribeck friction bump", "armature": "rotor inertia (armature)",
                "offset": "a torque-sensor offset", "gain": "a torque-sensor gain"}

_MOTOR_WORDS = {"motor_coulomb": "Coulomb friction", "motor_viscous": "viscous friction",
                "motor_armature": "rotor inertia"}


def overall_rms(per_joint: F64, measured: np.ndarray | None = None) -> float:
    """The RMS over the (measured) joints of per-joint RMS values (equal samples per
    joint)."""
    x = np.asarray(per_joint, dtype=float)
    return float(np.sqrt(np.mean((x if measured is None else x[measured]) ** 2)))


def _joints(ks: Sequence[int]) -> str:
    ks = [k + 1 for k in ks]
    if len(ks) == 1:
        return f"joint {ks[0]}"
    return "joints " + ", ".join(str(k) for k in ks[:-1]) + f" and {ks[-1]}"


def _loaded(e: FoundEffect, noise: F64) -> list[int]:
    """The joints whose torques the effect moves by more than their noise, largest first."""
    if e.rms_nm is None:
        return []
    order = np.argsort(-e.rms_nm)
    return [int(k) for k in order if e.rms_nm[k] > noise[k]]


def _part(e: FoundEffect) -> str:
    share = e.params["share"]
    mass = e.params.get("mass")
    part_kg = "" if mass is None else f" ({mass.value:.2f} kg)"
    if share.high >= 1.0 or share.value >= 0.9:
        return f"the model's {e.detail}{part_kg} is not on the arm"
    return f"the model's {e.detail} is lighter than modelled ({share.value:.0%} of it missing)"


def _payload(e: FoundEffect) -> str:
    m = e.params["mass"].value
    if m >= 0.0:
        return f"an undeclared payload of {m:.3g} kg at the tool"
    return f"the tool carries {-m:.3g} kg less than the model"


def effect_words(d: DynamicDiagnosis, e: FoundEffect) -> str:
    """One finding in words."""
    where = _loaded(e, d.noise_nm)
    on = f" (on {_joints(where[:3])})" if where else ""
    if e.name == "absent_part":
        return _part(e) + on
    if e.name == "payload":
        return _payload(e) + on
    if e.name == "link_mass":
        return _link_words(d, e) + on
    if e.name == "inertial":
        links = sorted(d.bodies.values(), key=lambda c: -float(np.max(c.torque_rms))
                       if c.torque_rms is not None else 0.0)
        names = ", ".join(c.name for c in links[:2])
        return "the link inertias (posture- and motion-dependent)" + (
            f", most on {names}" if names else "") + on
    if e.joint is not None and e.name in _JOINT_WORDS:
        p = next(iter(e.params.values()))
        return f"{_JOINT_WORDS[e.name]} on joint {e.joint + 1} ({p.value:.3g} {p.unit})"
    if e.name in _MOTOR_WORDS:
        p = next(iter(e.params.values()))
        turns = " and ".join(str(k + 1) for k in np.flatnonzero(e.rms_nm)) if (
            e.rms_nm is not None) else ""
        return (f"{_MOTOR_WORDS[e.name]} of {e.detail}, which turns with joints {turns} "
                f"({p.value:.3g} {p.unit} at joint scale)")
    return e.label


def _link_words(d: DynamicDiagnosis, e: FoundEffect) -> str:
    change = next((c for c in d.bodies.values() if c.name == e.detail), None)
    dm = e.params["mass"].value
    text = f"a posture-dependent (gravity) error: link {e.detail}'s mass {dm:+.3g} kg"
    if change is not None and change.centre_shift_m > 0.0:
        text += f", its centre moved {1000 * change.centre_shift_m:.0f} mm"
    return text


def _findings(d: DynamicDiagnosis) -> str:
    """The findings, the joint effects of one kind grouped."""
    parts: list[str] = []
    grouped: dict[str, list[FoundEffect]] = {}
    for e in d.found:
        if e.joint is not None and e.name in _JOINT_WORDS:
            if e.name not in grouped:
                parts.append(e.name)
            grouped.setdefault(e.name, []).append(e)
        else:
            parts.append(effect_words(d, e))
    out = []
    for p in parts:
        if p in grouped:
            out.append(f"{_JOINT_WORDS[p]} on {_joints([e.joint for e in grouped[p]])}")
        else:
            out.append(p)
    return "; ".join(out)


def _misses(before: F64, after: F64, noise: F64) -> str:
    order = [int(k) for k in np.argsort(-before)[:2]]
    return ", ".join(f"joint {k + 1} {before[k]:.3g} -> {after[k]:.3g} N m "
                     f"({after[k] / noise[k]:.1f}x its noise)" for k in order)


def validation_words(v: Validation) -> str:
    """The corrected model on the second log, in one sentence."""
    return (f"On another log ({v.source}, nothing refitted): {v.overall_before:.3g} -> "
            f"{v.overall_after:.3g} N m RMS ({v.overall_after / v.overall_noise:.2f}x its "
            f"noise floor of {v.overall_noise:.3g} N m).")


def headline(d: DynamicDiagnosis, validation: Validation | None = None) -> str:
    """The verdict's first paragraph (module docstring); with the second log's figures
    when the corrected model was scored on one."""
    text = _headline(d)
    return text if validation is None else f"{text} {validation_words(validation)}"


def _headline(d: DynamicDiagnosis) -> str:
    m = d.measured
    before, after = overall_rms(d.rms_before, m), overall_rms(d.rms_after, m)
    noise = overall_rms(d.noise_nm, m)
    removed = 1.0 - after / before if before > 0 else 0.0
    head = (f"Withheld torque error {before:.3g} -> {after:.3g} N m RMS over all joints "
            f"({removed:.0%} removed; noise floor {noise:.3g} N m). Largest misses: "
            f"{_misses(np.where(m, d.rms_before, 0.0), d.rms_after, d.noise_nm)}.")
    if d.data_problems:
        return head.split(" Largest")[0] + (" The log points at a data problem, not at the "
                                            "model (see Data problems): " + d.data_problems[0])
    if not d.found:
        return head.split(" Largest")[0] + (" The model's torques match the log down to the "
                                            "noise; no effect is needed.")
    ratio = np.where(m, d.rms_after / d.noise_nm, 0.0)
    left = [int(k) for k in np.argsort(-ratio) if ratio[k] > REMAINS]
    remains = ("What remains is at the noise floor." if not left else
               "What remains: " + ", ".join(f"joint {k + 1} at {ratio[k]:.1f}x its noise "
                                            f"({d.rms_after[k]:.3g} N m)" for k in left[:2])
               + ".")
    small = sum(e.small for e in d.effects)
    also = f" ({small} small effect{'s' if small > 1 else ''} too, listed apart)" if small else ""
    return f"{head} Found: {_findings(d)}{also}. {remains}"
