"""The verdict of a diagnosis in plain words (:attr:`zrp.gap.Diagnosis.verdict`)."""

from __future__ import annotations

import math

import numpy as np

from zrp.gap.results import Diagnosis, Step
from zrp.gap.where import WhereAnalysis

__all__ = ["remains_text", "verdict_text"]

#: R^2 below which the residual is said to depend on nothing in particular.
NO_TREND_R2 = 0.1
#: share of the residual common to a pose's points above which it behaves like a positioning
#: error of the robot.
POSE_ERROR_SHARE = 0.8


def _fmt(x: float | None, unit: str) -> str:
    return "n/a" if x is None else f"{x:.4g} {unit}"


def remains_text(w: WhereAnalysis, unit: str) -> str:
    """Plain words on the structure of what remains (from a where analysis)."""
    r2_joint = max((j.r2 for j in w.joints), default=0.0)
    r2_other = max([w.order_r2] + [r for r in (w.time_r2, w.temperature_r2) if r is not None])
    regions = w.regions
    inner = [g.rms for g in regions if g is regions[0] or g.radius == regions[0].radius]
    outer = [g.rms for g in regions if g.radius == regions[-1].radius]
    no_trend = r2_joint < NO_TREND_R2 and r2_other < NO_TREND_R2
    txt = []
    common = w.common_share
    if common is not None:
        txt.append(f"{100 * common:.0f} % of what remains moves all points of a pose together")
    if no_trend:
        txt.append(f"it depends on no single joint angle, the measurement order, time or "
                   f"temperature (R^2 <= {max(r2_joint, r2_other):.2f})")
    else:
        j = max(w.joints, key=lambda j: j.r2)
        txt.append(f"it still depends on q{j.joint} (R^2 {j.r2:.2f})" if j.r2 >= r2_other else
                   f"it still depends on measurement order/time/temperature (R^2 "
                   f"{r2_other:.2f})")
    if inner and outer:
        txt.append(f"RMS {np.mean(inner):.3g} {unit} in the inner and {np.mean(outer):.3g} "
                   f"{unit} in the outer third of the reach")
    out = "What remains: " + "; ".join(txt) + "."
    if common is not None and common > POSE_ERROR_SHARE and no_trend:
        out += (" This behaves like a pose-to-pose positioning error of the robot that no "
                "model correction of the joint angles or geometry reproduces (e.g. poor "
                "repeatability or settling); measuring repeated poses would tell the robot's "
                "own floor, which the rigid-link estimate (instrument noise only) does not.")
    return out


def _effects_found(steps: tuple[Step, ...]) -> list[str]:
    if not steps:
        return ["No effect in the library improves the model significantly (none)."]
    names = ", ".join(f"{s.effect} (joints {', '.join(map(str, s.joints)) or '-'})"
                      for s in steps)
    parts = [f"Effects found, in order: {names}."]
    for i, s in enumerate(steps, 1):
        if s.ties:
            parts.append(f"At step {i} {', '.join(s.ties)} explain(s) the data equally well; "
                         f"the data cannot tell {'them' if len(s.ties) > 1 else 'it'} apart "
                         f"from {s.effect}.")
    return parts


def _against_floor(diag: Diagnosis) -> list[str]:
    floor, final, unit = diag.noise_floor, diag.final, diag.length_unit
    if floor.rms is None:
        return ["The data allow no noise-floor estimate (one point per pose and no repeats), "
                "so whether a gap remains cannot be judged."]
    ratio = final.rms / floor.rms if floor.rms > 0 else math.inf
    parts = [f"Noise floor {_fmt(floor.rms, unit)} RMS ({floor.method}); the final error is "
             f"{ratio:.2g}x the floor."]
    if diag.unexplained:
        parts.append(f"A gap of {final.rms:.4g} {unit} RMS remains that no effect in the "
                     "library explains.")
        parts.append(remains_text(diag.where_final, unit))
    else:
        parts.append("What remains is at the noise floor.")
    return parts


def verdict_text(diag: Diagnosis) -> str:
    """One paragraph: the effects found (and ties), how far the withheld error shrinks, and
    how it compares with the noise floor (with the structure of an unexplained remainder)."""
    nominal, final, unit = diag.nominal, diag.final, diag.length_unit
    shrunk = 100 * (1 - final.rms / nominal.rms) if nominal.rms > 0 else 0
    parts = _effects_found(diag.steps)
    parts.append(f"Withheld RMS {nominal.rms:.4g} {unit} after registration, "
                 f"{final.rms:.4g} {unit} after correction ({shrunk:.0f} % smaller).")
    parts += _against_floor(diag)
    return " ".join(parts)
