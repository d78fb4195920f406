"""The effect library: each effect is a parametrised correction of the model.

Every parameter is a :class:`ParamSpec` of one *kind*, and the kind fixes how it enters the
corrected model (see :mod:`zrp.gap.model.problem`, which also gives the analytic Jacobian);
the parameter and the data context are :class:`~zrp.gap.model.context.ParamSpec` and
:class:`~zrp.gap.model.context.Context`:

* ``rot`` / ``trans``: the instrument-to-base registration (``base_frame``): a small rotation
  (rad, left-multiplied on the initial estimate) and the translation (length unit).
* ``tool``: one component of a tool point's offset t (length unit, zero-reference base frame;
  the point is p + R_n t).
* ``dq``: a joint correction q_actual = q + sum_i theta_i B_i(pose), with a fixed basis B of
  shape (P, n) per parameter. ``joint_offset`` (B = 1), ``encoder_scale`` (B = q),
  ``joint_compliance`` (B = gravity torque or a lumped-mass moment arm), ``backlash``
  (B = -approach direction / 2 per unit of full play, or half the sign of the gravity torque
  where it exceeds a per-joint threshold so that the joint rests on the loaded flank of its
  play), ``cyclic_error``
  (B = sin(h q), cos(h q)) are all of this kind.
* ``link``: one component of a body-vector correction db_{k,0} (length unit).
* ``tilt``: a tilt of a joint axis towards one of its tangents t1, t2 (rad), exact:
  u' = (u + a t1 + b t2) / |u + a t1 + b t2| (tangents from
  :func:`zrp.kinematics.identification.axis_tangents`).
* ``thermal``: all body vectors scale by (1 + kappa (temp - T_ref)), kappa in 1/deg C.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import EFFECTS, Context, ParamSpec
from zrp.gap.model.jointbases import joint_bases

__all__ = ["Built", "effect_parameters", "registration_parameters"]


def registration_parameters(ctx: Context) -> list[ParamSpec]:
    """``base_frame`` (unless the data are in the base frame) and ``tool_offset`` specs."""
    unit = ctx.model.length_unit
    specs: list[ParamSpec] = []
    if ctx.meas.frame == "instrument":
        specs += [ParamSpec(f"base.r{c}", "rad", "base_frame", "rot", 0, i, group="base")
                  for i, c in enumerate("xyz")]
        specs += [ParamSpec(f"base.t{c}", unit, "base_frame", "trans", 0, i, group="base")
                  for i, c in enumerate("xyz")]
    for m, lab in enumerate(ctx.meas.point_labels):
        specs += [ParamSpec(f"tool[{lab}].{c}", unit, "tool_offset", "tool", 0, 3 * m + i,
                            group=f"tool[{lab}]") for i, c in enumerate("xyz")]
    return specs


def _dq(ctx: Context, name: str, unit: str, effect: str, k: int, col: F64,
        group: str | None = None) -> ParamSpec:
    basis = np.zeros(ctx.q.shape)
    basis[:, k] = col
    basis.setflags(write=False)
    return ParamSpec(name, unit, effect, "dq", k + 1, 0, basis, group or f"q{k + 1}")


def _junits(ctx: Context) -> list[str]:
    """Unit of each joint's value: rad, or the length unit for prismatic joints."""
    return [ctx.model.length_unit if p else "rad" for p in ctx.model.prismatic]


#: what an effect builder returns: the specs, and None or why the effect cannot be tried.
Built = tuple[list[ParamSpec], str | None]


def _joint_offset(ctx: Context) -> Built:
    junit = _junits(ctx)
    b = joint_bases(ctx, "joint_offset")["offset"]
    return [_dq(ctx, f"q{k + 1}.offset", junit[k], "joint_offset", k, b[:, k])
            for k in range(ctx.n)], None


def _encoder_scale(ctx: Context) -> Built:
    b = joint_bases(ctx, "encoder_scale")["scale"]
    return [_dq(ctx, f"q{k + 1}.scale", "1", "encoder_scale", k, b[:, k])
            for k in range(ctx.n)], None


def _cyclic_error(ctx: Context) -> Built:
    rev = [k for k in range(ctx.n) if not ctx.model.prismatic[k]]
    if not rev:
        return [], "no revolute joint"
    b = joint_bases(ctx, "cyclic_error")
    return [_dq(ctx, f"q{k + 1}.{fn}{h}", "rad", "cyclic_error", k, b[f"{fn}{h}"][:, k])
            for k in rev for h in ctx.harmonics for fn in ("sin", "cos")], None


def _backlash(ctx: Context) -> Built:
    """One full play b per joint (the definition of ``zrp measure``): the joint sits b/2 off
    the centre of its play, so the basis is half the flank side
    (:mod:`zrp.gap.model.jointbases`)."""
    junit = _junits(ctx)
    basis = joint_bases(ctx, "backlash")["backlash"]
    specs = [_dq(ctx, f"q{k + 1}.backlash", junit[k], "backlash", k, basis[:, k])
             for k in range(ctx.n) if np.any(basis[:, k] > 0) and np.any(basis[:, k] < 0)]
    if not specs:
        return [], ("no joint approaches its poses from both directions or sees gravity "
                    "torques of both signs")
    return specs, None


def _compliance_mjcf(ctx: Context) -> Built:
    """One compliance per joint (rad per N m) on the given gravity torques, and one per joint
    for an unknown payload at the tool (it adds c_k m g h_ee: linear in c_k m)."""
    effect = "joint_compliance"
    junit = _junits(ctx)
    b = joint_bases(ctx, effect)
    tau, pay = b["compliance"], b["compliance_payload"]
    specs: list[ParamSpec] = []
    for k in range(ctx.n):
        if np.ptp(tau[:, k]) > 0 or np.any(tau[:, k] != 0):
            specs.append(_dq(ctx, f"q{k + 1}.compliance", f"{junit[k]}/(N m)", effect, k,
                             tau[:, k]))
        if np.any(pay[:, k] != 0.0):
            specs.append(_dq(ctx, f"q{k + 1}.compliance_payload", f"{junit[k]}/kg", effect, k,
                             pay[:, k]))
    return specs, None


def _compliance_lumped(ctx: Context) -> Built:
    """One weight per joint and lumped mass point (rad per length unit), and one per joint
    for a varying ``load`` column."""
    effect = "joint_compliance"
    unit = ctx.model.length_unit
    load = ctx.meas.per_pose("load")
    labels, _ = ctx.moment_arms()
    h_ee = ctx.end_effector_arms()
    b = joint_bases(ctx, effect)
    specs: list[ParamSpec] = []
    for k in range(ctx.n):
        specs += [_dq(ctx, f"q{k + 1}.w_{lab}", f"rad/{unit}", effect, k, b[f"w_{lab}"][:, k])
                  for lab in labels if np.any(b[f"w_{lab}"][:, k] != 0.0)]
        if load is not None and np.ptp(load) > 0 and np.any(h_ee[:, k] != 0.0):
            specs.append(_dq(ctx, f"q{k + 1}.w_load", f"rad/({unit} kg)", effect, k,
                             b["w_load"][:, k]))
    return specs, (None if specs else "no joint carries a gravity torque")


def _joint_compliance(ctx: Context) -> Built:
    return _compliance_mjcf(ctx) if ctx.gravity_torque is not None else _compliance_lumped(ctx)


def _link_length(ctx: Context) -> Built:
    unit = ctx.model.length_unit
    return [ParamSpec(f"b{k + 1}.{c}", unit, "link_length", "link", k + 1, i,
                      group=f"b{k + 1}")
            for k in range(ctx.n + 1) for i, c in enumerate("xyz")], None


def _axis_misalignment(ctx: Context) -> Built:
    return [ParamSpec(f"u{k + 1}.t{t + 1}", "rad", "axis_misalignment", "tilt", k + 1, t,
                      group=f"q{k + 1}") for k in range(ctx.n) for t in range(2)], None


def _thermal_expansion(ctx: Context) -> Built:
    if ctx.dtemp is None:
        return [], "no temp column"
    if np.ptp(ctx.dtemp) < 0.1:
        return [], f"temp varies by only {np.ptp(ctx.dtemp):.3g} deg C"
    return [ParamSpec("kappa", "1/degC", "thermal_expansion", "thermal", 0, 0,
                      group="kappa")], None


_BUILDERS: dict[str, Callable[[Context], Built]] = {
    "joint_offset": _joint_offset,
    "encoder_scale": _encoder_scale,
    "link_length": _link_length,
    "axis_misalignment": _axis_misalignment,
    "joint_compliance": _joint_compliance,
    "backlash": _backlash,
    "thermal_expansion": _thermal_expansion,
    "cyclic_error": _cyclic_error,
}


def effect_parameters(ctx: Context, effect: str) -> tuple[list[ParamSpec], str | None]:
    """The full (possibly redundant) parameter set of one effect.

    Returns:
        the specs, and None, or an empty list and the reason the effect cannot be tried
        (e.g. ``thermal_expansion`` without a ``temp`` column).
    """
    if effect not in EFFECTS:
        raise InputError(f"effect: {effect!r} is not an effect; valid: {', '.join(EFFECTS)}")
    return _BUILDERS[effect](ctx)
