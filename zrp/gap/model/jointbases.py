"""The bases of the joint-correction parameters: one definition for the diagnosis and for the
calibrated robot.

Every joint-space parameter theta of an effect enters the corrected model as a joint
correction dq_k = theta B_k(pose) (zrp/gap/README.md). :func:`joint_bases` gives the bases of
an effect for every joint on the poses of a :class:`zrp.gap.model.context.Context`, before anything
is dropped: the effect builders (:mod:`zrp.gap.model.effects`) keep the joints the poses excite, and
:mod:`zrp.calibration.jointmap` re-evaluates the identified ones on new poses (targets), so a
change here changes both alike.

==========================  =============================================================
parameter ``q{k}.{what}``   basis B_k per pose
==========================  =============================================================
``offset``                  1
``scale``                   q_k (encoder scale: q_actual = q (1 + s))
``sin{h}``, ``cos{h}``      sin(h q_k), cos(h q_k) (cyclic error, h in the harmonics)
``backlash``                half the flank side (the parameter is the full play b: the
                            joint sits b/2 off the centre of its play): 0.5 x
                            (-approach direction, or sign(tau_k) above the switching torque)
``compliance``              gravity torque tau_k (MJCF) + g load h_ee (N m)
``compliance_payload``      g h_ee (m) (an unknown payload at the tool)
``w_{p}``                   lumped-mass moment arms (length unit; without MJCF torques)
``w_load``                  load x h_ee (kg x length unit; zero without a load column)
==========================  =============================================================
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import Context
from zrp.units import G_STANDARD, metres_per_unit

__all__ = ["JOINT_EFFECTS", "joint_bases"]


#: effects whose parameters are joint corrections with a pose-dependent basis.
JOINT_EFFECTS = ("joint_offset", "encoder_scale", "cyclic_error", "backlash",
                 "joint_compliance")


def _compliance(ctx: Context) -> dict[str, F64]:
    load = ctx.meas.per_pose("load")
    h_ee = ctx.end_effector_arms()
    if ctx.gravity_torque is not None:
        to_m = metres_per_unit(ctx.model.length_unit, "model.length_unit")
        tau = np.array(ctx.gravity_torque, dtype=float)
        if load is not None:
            tau = tau + G_STANDARD * load[:, None] * h_ee * to_m
        return {"compliance": tau, "compliance_payload": G_STANDARD * h_ee * to_m}
    labels, h = ctx.moment_arms()
    h = np.where(np.abs(h) > 1e-9 * ctx.model.characteristic_length, h, 0.0)
    out = {f"w_{lab}": h[:, :, jj] for jj, lab in enumerate(labels)}
    out["w_load"] = np.zeros_like(h_ee) if load is None else load[:, None] * h_ee
    return out


def joint_bases(ctx: Context, effect: str) -> dict[str, F64]:
    """The bases of ``effect``'s joint-correction parameters on the poses of ``ctx``.

    Returns:
        ``what`` -> B, shape (P, n): column k is the basis of parameter ``q{k+1}.{what}``
        (model joint units per parameter unit; see the module table). Every joint is
        included; which ones a diagnosis may fit is the effect builder's choice.

    Raises:
        InputError: ``effect`` has no joint-correction parameters.
    """
    q = np.array(ctx.q, dtype=float)
    if effect == "joint_offset":
        return {"offset": np.ones_like(q)}
    if effect == "encoder_scale":
        return {"scale": q}
    if effect == "cyclic_error":
        return {f"{fn}{h}": (np.sin(h * q) if fn == "sin" else np.cos(h * q))
                for h in ctx.harmonics for fn in ("sin", "cos")}
    if effect == "backlash":
        return {"backlash": 0.5 * ctx.backlash_basis()}
    if effect == "joint_compliance":
        return _compliance(ctx)
    raise InputError(f"effect: {effect!r} has no joint-correction parameters; expected one "
                     f"of {', '.join(JOINT_EFFECTS)}")
