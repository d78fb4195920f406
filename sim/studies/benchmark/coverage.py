"""Blind benchmark, part 3b: do the diagnosis's 95 % intervals cover the hidden true values?

For the hidden effect of a scenario, every parameter of that effect in the diagnosis's final
model (``final.parameters`` of diagnosis.json, robust 95 % intervals) is compared with its true
value: the injected one, or 0 on joints where the effect was not injected. Definitions match
(see sim/robot/effects.py and zrp/gap/README.md): ``q{k}.offset`` (motor = q + offset),
``q{k}.scale`` (q (1 + s)), ``q{k}.sin{h}``/``cos{h}`` (cyclic amplitudes, rad),
``q{k}.backlash`` (the full play b), ``q{k}.compliance`` (rad/(N m)), ``u{k}.t1``/``t2``
(axis tilts, rad) and ``kappa`` (1/K). Body-vector corrections (``link_length``) are not
compared: the diagnosis estimates a QR-reduced base set whose members absorb their aliased
partners, so no single value has a truth of its own.

A scenario counts as covered when every compared parameter is. With each parameter's own 95 %
interval that is a simultaneous statement the intervals are not built for: even exact
intervals cover all 4 terms of a cyclic error together only 0.95^4 = 81 % of the time. So the
scenario count is also given with ``ci95_effect``, the diagnosis's simultaneous 95 % intervals
over all parameters of the effect (Sidak; :func:`zrp.gap.fit.uncertainty.simultaneous_z`), which
are built for exactly that statement.
"""

from __future__ import annotations

from collections.abc import Sequence

from sim.robot.effects import HiddenEffects
from zrp.gap.results import ParameterEstimate

__all__ = ["COMPARABLE", "interval_coverage", "true_values"]

#: hidden effects whose parameters have a true value to compare with.
COMPARABLE = ("joint_offset", "encoder_scale", "cyclic_error", "backlash", "joint_compliance",
              "axis_misalignment", "thermal_expansion")


def true_values(eff: HiddenEffects, effect: str) -> dict[str, float]:
    """Parameter name of the diagnosis -> true value, for the joints the effect is on."""
    v = getattr(eff, effect)
    out: dict[str, float] = {}
    if effect == "joint_offset":
        out = {f"q{k}.offset": float(x) for k, x in v.items()}
    elif effect == "encoder_scale":
        out = {f"q{k}.scale": float(x) for k, x in v.items()}
    elif effect == "backlash":
        out = {f"q{k}.backlash": float(x) for k, x in v.items()}
    elif effect == "joint_compliance":
        out = {f"q{k}.compliance": float(x) for k, x in v.items()}
    elif effect == "cyclic_error":
        for k, (h, a, b) in v.items():
            out[f"q{k}.sin{int(h)}"] = float(a)
            out[f"q{k}.cos{int(h)}"] = float(b)
    elif effect == "axis_misalignment":
        for k, (a, b) in v.items():
            out[f"u{k}.t1"], out[f"u{k}.t2"] = float(a), float(b)
    elif effect == "thermal_expansion":
        out = {"kappa": float(v)}
    return out


def interval_coverage(eff: HiddenEffects, hidden: tuple[str, ...],
                      parameters: Sequence[ParameterEstimate], key: str = "ci95"
                      ) -> tuple[int, int, list[str]]:
    """(covered, compared, misses) over ``parameters``, the final model's (a diagnosis's
    ``final_parameters``), for the hidden effects; a miss reads "name: true x not in [lo, hi]".
    ``key``: ``"ci95"`` (each parameter's 95 % interval) or ``"ci95_effect"`` (the
    simultaneous 95 % intervals of the whole effect)."""
    covered, total, misses = 0, 0, []
    for effect in hidden:
        if effect not in COMPARABLE:
            continue
        truth = true_values(eff, effect)
        for p in parameters:
            interval = getattr(p, key)
            if p.effect != effect or interval is None:
                continue
            if effect == "joint_compliance" and not p.name.endswith(".compliance"):
                continue  # the payload terms: their truth depends on the unknown payload
            lo, hi = interval
            t = truth.get(p.name, 0.0)
            total += 1
            if lo <= t <= hi:
                covered += 1
            else:
                misses.append(f"{p.name}: true {t:.3g} not in [{lo:.3g}, {hi:.3g}]")
    return covered, total, misses
