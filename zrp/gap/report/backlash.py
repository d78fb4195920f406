"""The report's sentence on where each joint with play rests (eq. B1 of
:mod:`zrp.gap.fit.profiles`): on the flank gravity loads above its switching torque, else
lagging behind or leading its approach, as the diagnosis profiled it."""

from __future__ import annotations

import math

from zrp.gap.results import Diagnosis

__all__ = ["backlash_flank_text"]


def _side(switch: float | None, lead: bool, unit: str) -> str:
    side = ("ahead of the approach, on the leading flank (as when the load's inertia carries "
            "it over while the motor stops)" if lead else
            "behind the approach, on the lagging flank (as when the load's friction holds it "
            "back)")
    if switch is None or not math.isfinite(switch):
        return side
    if switch == 0.0:
        return "on the flank gravity loads"
    return (f"on the flank gravity loads where |gravity torque| > {switch:.3g} {unit}, below "
            f"that {side}")


def backlash_flank_text(diag: Diagnosis) -> str:
    """One paragraph, or "" when the final model has no backlash."""
    joints = diag.final_joints.get("backlash", ())
    bl = diag.where.backlash
    if not joints or bl is None:
        return ""
    unit = "N m" if diag.context.gravity_torque is not None else "(lumped-mass torque units)"
    lead = bl.lead or (False,) * len(bl.switch)
    groups: dict[str, list[int]] = {}
    for k in joints:
        groups.setdefault(_side(bl.switch[k - 1], bool(lead[k - 1]), unit), []).append(k)
    parts = [f"joint{'s' if len(ks) > 1 else ''} {', '.join(map(str, ks))}: {side}"
             for side, ks in groups.items()]
    text = "Where each joint with play rests (profiled on the fitting poses): " + "; ".join(
        parts) + "."
    if bl.payload_kg:
        text += (f" The gravity torques include an unknown payload of {bl.payload_kg:g} kg at "
                 "the tool, profiled with the flanks.")
    return text
