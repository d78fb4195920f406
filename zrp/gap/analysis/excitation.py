"""Which joints the data excite: no per-joint function of a joint's angle (scale, cyclic
error, backlash) is placed on a joint that barely moves
(:attr:`zrp.gap.model.context.Context.excited`, threshold
:data:`zrp.gap.model.context.MIN_EXCITATION_RAD`)."""

from __future__ import annotations

from zrp.gap.model.context import Context
from zrp.gap.model.effects import Built

__all__ = ["PER_JOINT_ANGLE", "excited_only"]

#: effects that are a function of one joint's own angle: only on joints the data excite.
PER_JOINT_ANGLE = ("encoder_scale", "cyclic_error", "backlash")


def excited_only(ctx: Context, built: Built) -> Built:
    """``built`` without the parameters of :data:`PER_JOINT_ANGLE` effects on joints that
    :attr:`Context.excited` says barely move (the survey still sees them all)."""
    specs, why = built
    keep = [s for s in specs if s.effect not in PER_JOINT_ANGLE or s.joint == 0
            or ctx.excited[s.joint - 1]]
    if specs and not keep:
        return [], "no joint moves enough"
    return keep, why
