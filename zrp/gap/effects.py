"""The effect library: each effect is a parametrised correction of the model.

Every parameter is a :class:`ParamSpec` of one *kind*, and the kind fixes how it enters the
corrected model (see :mod:`zrp.gap.problem`, which also gives the analytic Jacobian):

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
  :func:`zrp.manufacturing.axis_tangents`).
* ``thermal``: all body vectors scale by (1 + kappa (temp - T_ref)), kappa in 1/deg C.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.data import Measurements
from zrp.gap.jointbases import joint_bases
from zrp.kinematics.forward import forward_kinematics
from zrp.kinematics.identification import axis_tangents
from zrp.model.manipulator import Manipulator
from zrp.units import G_STANDARD, metres_per_unit

__all__ = [
    "EFFECTS",
    "KINDS",
    "MIN_EXCITATION_RAD",
    "REGISTRATION",
    "Context",
    "ParamSpec",
    "effect_parameters",
    "registration_parameters",
]

F64 = NDArray[np.float64]

#: Candidate effects, in the order they are tried (ties are broken by this order).
EFFECTS = ("joint_offset", "encoder_scale", "link_length", "axis_misalignment",
           "joint_compliance", "backlash", "thermal_expansion", "cyclic_error")
REGISTRATION = ("base_frame", "tool_offset")
#: A revolute joint must span at least this range (rad, 2 deg) over the poses to carry an
#: encoder scale, a cyclic error or backlash (prismatic: this fraction of the reach).
MIN_EXCITATION_RAD = float(np.radians(2.0))
KINDS = ("rot", "trans", "tool", "dq", "link", "tilt", "thermal")


@dataclass(frozen=True, eq=False)
class ParamSpec:
    """One parameter of the corrected model.

    Attributes:
        name: e.g. "q2.offset", "b3.x", "u4.t1", "base.rz", "tool[smr1].x".
        unit: e.g. "rad", "mm", "1", "1/degC", "rad/mm".
        effect: one of :data:`EFFECTS` or :data:`REGISTRATION`.
        kind: one of :data:`KINDS` (how it enters the model).
        joint: 1-based joint (or body-vector index for ``link``); 0 when not joint-specific.
        comp: component/index within the kind (xyz component, tangent 0/1, tool point index).
        basis: for ``dq`` only, the joint correction per unit parameter, shape (P, n).
        group: parameters tested together for significance (e.g. all of one joint).
    """

    name: str
    unit: str
    effect: str
    kind: str
    joint: int = 0
    comp: int = 0
    basis: F64 | None = None
    group: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"ParamSpec {self.name}: kind {self.kind!r} not in {KINDS}")
        if self.effect not in EFFECTS + REGISTRATION:
            raise InputError(f"ParamSpec {self.name}: effect {self.effect!r} not in "
                             f"{EFFECTS + REGISTRATION}")
        if (self.kind == "dq") != (self.basis is not None):
            raise InputError(f"ParamSpec {self.name}: a basis is required for kind 'dq' only")
        if not self.group:
            object.__setattr__(self, "group", self.name)


@dataclass(frozen=True, eq=False)
class Context:
    """Everything the effects need about the data, per pose (P poses, n joints).

    Attributes:
        model: the nominal model.
        meas: the measurements.
        gravity_torque: gravity torque per joint from MJCF inertias, shape (P, n), or None
            (then the lumped-mass model is used).
        gravity_dir: unit direction of gravity in the base frame, shape (3,).
        harmonics: harmonics of ``cyclic_error`` (periods 2 pi / h in the joint angle).
        t_ref_degC: reference temperature of ``thermal_expansion``, deg C (default 20, the
            ISO 1 reference temperature at which the nominal lengths are taken to hold).
        gravity_side: a torque per pose and joint whose sign tells which side of its play a
            gravity-loaded joint rests against, shape (P, n), or None (see
            :meth:`gravity_side_torque`).
        backlash_switch: per joint, the gravity torque (units of
            :meth:`gravity_side_torque`) above which the joint rests on the loaded flank of its
            play instead of lagging against its approach direction; inf (the default) means
            always the approach direction, 0 always the loaded flank.
        backlash_switch_weights: per joint, plausible switching torques and their weights
            (profile likelihood); poses whose torque lies among them get the weighted mean of
            the two flanks instead of a hard choice. None: use ``backlash_switch`` alone.
        payload_kg: a payload at the tool that the MJCF torques lack, kg (added to them for
            the backlash flank; the diagnosis profiles it).
    """

    model: Manipulator
    meas: Measurements
    gravity_torque: F64 | None = None
    gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0)
    harmonics: tuple[int, ...] = (1, 2)
    t_ref_degC: float = 20.0
    gravity_side: F64 | None = None
    backlash_switch: tuple[float, ...] | None = None
    backlash_switch_weights: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] | None = None
    payload_kg: float = 0.0

    def __post_init__(self) -> None:
        if self.meas.n_joints != self.model.n:
            raise InputError(f"measurements have {self.meas.n_joints} joint columns but the model "
                             f"{self.model.name!r} has {self.model.n} joints")
        g = np.asarray(self.gravity_dir, dtype=float)
        if g.shape != (3,) or not np.isclose(np.linalg.norm(g), 1.0):
            raise InputError(f"gravity_dir: expected a unit 3-vector, got {self.gravity_dir}")
        if self.gravity_torque is not None and np.shape(self.gravity_torque) != (
                len(self.meas.pose_ids), self.model.n):
            raise InputError(f"gravity_torque: expected shape ({len(self.meas.pose_ids)}, "
                             f"{self.model.n}), got {np.shape(self.gravity_torque)}")
        if not self.harmonics or any(int(h) < 1 for h in self.harmonics):
            raise InputError(f"harmonics: expected positive integers, got {self.harmonics}")

    @property
    def n(self) -> int:
        return self.model.n

    @cached_property
    def q(self) -> F64:
        """Joint values per pose, shape (P, n)."""
        return self.meas.q_pose

    @cached_property
    def excited(self) -> NDArray[np.bool_]:
        """Joints that move enough for a per-joint function of their angle (scale, cyclic
        error, backlash) to be told from noise: spread of the joint value over the poses of at
        least :data:`MIN_EXCITATION_RAD` (revolute) or that fraction of the reach (prismatic),
        shape (n,). A joint below it (e.g. a 0.1 deg jitter) carries none of these effects."""
        spread = np.ptp(self.q, axis=0) if len(self.q) else np.zeros(self.n)
        lim = np.where(np.asarray(self.model.prismatic), MIN_EXCITATION_RAD
                       * self.model.characteristic_length, MIN_EXCITATION_RAD)
        return spread >= lim

    @cached_property
    def tangents(self) -> F64:
        """Axis tangents t1, t2 of each nominal axis, shape (n, 2, 3)."""
        return axis_tangents(self.model.axes)

    @cached_property
    def t_ref(self) -> float | None:
        temp = self.meas.per_pose("temp")
        if temp is None:
            return None
        return float(self.t_ref_degC)

    @cached_property
    def dtemp(self) -> F64 | None:
        """temp - T_ref per pose, deg C, shape (P,), or None."""
        temp = self.meas.per_pose("temp")
        return None if temp is None else temp - float(self.t_ref)  # type: ignore[arg-type]

    @cached_property
    def nominal_fk(self):  # noqa: ANN201
        return forward_kinematics(self.model, self.q)

    def backlash_basis(self) -> F64:
        """Which side of its play each joint sits on in each pose, shape (P, n), in [-1, 1] per
        unit play: -approach direction where |gravity torque| <= the joint's
        :attr:`backlash_switch`, else the sign of the gravity torque; with
        :attr:`backlash_switch_weights`, the weighted mean over the plausible switches."""
        d = self.meas.approach_direction()
        tau = self.gravity_side_torque()
        sw = (np.full(self.n, np.inf) if self.backlash_switch is None
              else np.asarray(self.backlash_switch, dtype=float))
        out = np.where(np.abs(tau) > sw, np.sign(tau), -d)
        if self.backlash_switch_weights is not None:
            for k, (thr, w) in enumerate(self.backlash_switch_weights):
                t = np.asarray(thr, dtype=float)
                p_g = (np.abs(tau[:, k])[:, None] > t[None, :]) @ np.asarray(w, dtype=float)
                out[:, k] = p_g * np.sign(tau[:, k]) - (1.0 - p_g) * d[:, k]
        return out

    def gravity_side_torque(self) -> F64:
        """A gravity torque per pose and joint whose sign is trusted, shape (P, n): the MJCF
        torque when given, else ``gravity_side`` (the diagnosis sets it from a lumped-mass
        compliance fit), else equal unit masses at the lumped mass points (length unit);
        values below 1e-6 of the largest are set to 0 (no load)."""
        if self.gravity_torque is not None:
            tau = np.array(self.gravity_torque, dtype=float)
            if self.payload_kg:
                tau = tau + (G_STANDARD * self.payload_kg * self.end_effector_arms()
                             * metres_per_unit(self.model.length_unit, "model.length_unit"))
        elif self.gravity_side is not None:
            tau = np.array(self.gravity_side, dtype=float)
        else:
            _, h = self.moment_arms()
            tau = h.sum(axis=2)
        big = np.abs(tau).max(axis=0, keepdims=True)
        return np.where(np.abs(tau) > 1e-6 * np.where(big > 0, big, 1.0), tau, 0.0)

    def end_effector_arms(self) -> F64:
        """Moment arm of the end-effector point about each joint, u_k . ((p - p_k) x g_dir),
        shape (P, n) (length unit; 0 for prismatic joints and below 1e-9 of the reach)."""
        fk = self.nominal_fk
        g = np.asarray(self.gravity_dir, dtype=float)
        arm = np.cross(fk.position[:, None, :] - fk.points, g)
        h = np.einsum("pki,pki->pk", fk.axes, arm)
        h[:, np.asarray(self.model.prismatic)] = 0.0
        return np.where(np.abs(h) > 1e-9 * self.model.characteristic_length, h, 0.0)

    def moment_arms(self) -> tuple[list[str], F64]:
        """Lumped-mass moment arms h[p, k, j] = u_k . ((P_j - p_k) x g_dir) (length unit).

        Mass points P_j: the points on joints 2..n and the end effector (points that coincide
        at q = 0 are merged). Returns the point labels (J,) and h, shape (P, n, J); entries of
        points not beyond joint k are 0.
        """
        fk = self.nominal_fk
        n = self.n
        g = np.asarray(self.gravity_dir, dtype=float)
        zero = forward_kinematics(self.model, np.zeros(n))
        labels: list[str] = []
        cols: list[F64] = []
        owners: list[int] = []
        seen: list[F64] = []
        for j in range(1, n + 1):  # 0-based joint j -> point on joint j+1; j == n: the ee
            pz = zero.position if j == n else zero.points[j]
            if any(np.linalg.norm(pz - s) < 1e-9 for s in seen):
                continue
            seen.append(pz)
            labels.append("ee" if j == n else f"p{j + 1}")
            cols.append(fk.position if j == n else fk.points[:, j])
            owners.append(j)
        h = np.zeros((self.q.shape[0], n, len(cols)))
        for jj, (pt, owner) in enumerate(zip(cols, owners, strict=False)):
            for k in range(n):
                if k >= owner or self.model.prismatic[k]:
                    continue
                arm = np.cross(pt - fk.points[:, k], g)
                h[:, k, jj] = np.einsum("pi,pi->p", fk.axes[:, k], arm)
        return labels, h


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
    the centre of its play, so the basis is half the flank side (:mod:`zrp.gap.jointbases`)."""
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
