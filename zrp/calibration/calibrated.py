"""The calibrated robot taken out of a gap diagnosis (:class:`CalibratedRobot`).

Geometric part (a :class:`~zrp.Manipulator`, written as a model TOML): the diagnosis's
corrected geometry (body vectors b_k + db_k, tilted axes) with the identified revolute joint
offsets delta folded in. Folding is exact: with R_{k-1}(delta) the rotation before body k at
q = delta,

    u'_k = R_{k-1}(delta) u_k,   b'_k = R_{k-1}(delta) b_k,   t'_j = R_n(delta) t_j,

and FK'(x) = FK(x + delta) for every x (the zero reference position moves to q = delta; the
product of axis rotations commutes past R_{k-1}(delta)). Non-geometric part (the
compensation file): the joint map :mod:`zrp.calibration.jointmap` (encoder scales, cyclic
error, compliance, backlash, prismatic offsets), thermal expansion kappa, the
instrument-from-base transform (R_b, t_b) and the tool points t'_j in full. The prediction is

    m_ij = R_b (p'(x_i) + R'_n(x_i) t'_j) + t_b,   x_i = q_i + dq(q_i, pose conditions)

with p', R'_n the forward kinematics of the folded geometry, bodies scaled by
1 + kappa (temp - t_ref) -- the diagnosis's corrected model (zrp/gap/README.md) term by term.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.calibration.conditions import Conditions
from zrp.calibration.jointmap import NON_GEOMETRIC, Term, joint_correction
from zrp.calibration.learned import LearnedTerm, check_learned, correct_hand
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements
from zrp.gap.finalrecord import FinalModelRecord, final_model_record
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.model.context import Context
from zrp.gap.results import Diagnosis
from zrp.model.manipulator import Manipulator
from zrp.rotations import skew

__all__ = ["CalibratedRobot", "PoseConditions", "chain", "rotation_about"]


def rotation_about(u: F64, angle: float) -> F64:
    """Rotation about unit axis u (3,) by ``angle`` (rad), shape (3, 3) (Rodrigues)."""
    return _rot(np.asarray(u, dtype=float), np.array([angle]))[0]


def _rot(u: F64, q: F64) -> F64:
    """Rotations about unit axis u (3,) by angles q (S,): (S, 3, 3)."""
    k = skew(u)
    return (np.eye(3) + np.sin(q)[:, None, None] * k
            + (1.0 - np.cos(q))[:, None, None] * (k @ k))


def chain(model: Manipulator, x: F64, scale: F64 | None = None) -> tuple[F64, F64, F64, F64]:
    """Forward kinematics of ``model`` at joint values x (S, n), bodies scaled per pose.

    Returns:
        end point p (S, 3), hand rotation R_n (S, 3, 3), joint points p_k (S, n, 3) and
        current axes u_k (S, n, 3), all in the base frame (length unit).
    """
    S, n = x.shape
    s = np.ones(S) if scale is None else scale
    r = np.broadcast_to(np.eye(3), (S, 3, 3))
    pos = np.zeros((S, 3))
    pts = np.empty((S, n, 3))
    axes = np.empty((S, n, 3))
    u0, b0 = model.axes, model.bodies
    for k in range(n + 1):
        pos = pos + s[:, None] * (r @ b0[k])
        if k == n:
            break
        pts[:, k] = pos
        axes[:, k] = r @ u0[k]
        if model.prismatic[k]:
            pos = pos + x[:, k, None] * axes[:, k]
        else:
            r = r @ _rot(u0[k], x[:, k])
    return pos, np.array(r), pts, axes


def _joint_terms(rec: FinalModelRecord, model: Manipulator
                 ) -> tuple[F64, list[Term], float]:
    """The revolute offsets to fold (n,), the joint-map terms and kappa of a record."""
    delta = np.zeros(model.n)
    terms: list[Term] = []
    kappa = 0.0
    for s in rec.parameters:
        if s.kind == "thermal":
            kappa = float(s.value)
        elif s.kind == "dq" and s.effect == "joint_offset" and not model.prismatic[s.joint - 1]:
            delta[s.joint - 1] = float(s.value)
        elif s.kind == "dq" and s.effect in NON_GEOMETRIC:
            terms.append(Term(s.name, s.effect, s.joint, s.unit, float(s.value),
                              float(s.stderr)))
    return delta, terms, kappa


@dataclass(frozen=True)
class PoseConditions:
    """What the joint map needs besides the commanded joint values (P poses, n joints).

    Attributes:
        direction: approach direction per pose and joint (-1/0/+1), shape (P, n), or None
            (from the order of the poses, as :meth:`zrp.gap.Measurements.approach_direction`).
        gravity_torque: MJCF gravity torque per pose and joint (N m), shape (P, n), or None
            (required when the compliance was identified with MJCF torques).
        temp: temperature per pose, deg C, shape (P,), or None (the reference temperature).
        load: payload per pose, kg, shape (P,), or None.
    """

    direction: ArrayLike | None = None
    gravity_torque: ArrayLike | None = None
    temp: ArrayLike | None = None
    load: ArrayLike | None = None


@dataclass(frozen=True, eq=False)
class CalibratedRobot:
    """A calibrated robot: folded geometry plus the non-geometric corrections.

    Attributes:
        model: the calibrated geometry (offsets, body vectors, axis tilts folded in).
        nominal: the nominal model the diagnosis started from (the lumped-mass moment arms of
            the joint map are its, as in the diagnosis).
        base_rotation: R_b, instrument-from-base rotation, shape (3, 3) (identity for data
            in the base frame).
        base_translation: t_b, shape (3,) (length unit).
        tool_labels: tool point labels (M,).
        tool_points: t'_j, offsets of the tool points from the model's end point in the
            calibrated zero reference position, shape (M, 3) (length unit).
        joint_offsets: the revolute offsets folded into ``model`` (rad), shape (n,) (for the
            record: commands are in the robot's own joint values).
        terms: the joint-map terms.
        kappa: thermal expansion, 1/deg C (0: none identified); t_ref: its reference, deg C.
        backlash_switch: per joint, the gravity torque above which the joint rests on its
            loaded flank (None: approach direction only).
        payload_kg: the payload the diagnosis profiled for the backlash flank.
        gravity_dir, harmonics, frame: as in the diagnosis.
        compliance_model: "mjcf" or "lumped_masses".
        withheld_rms: the diagnosis's final withheld RMS (length unit), for the record.
        gravity_side_weights: without MJCF torques, the lumped masses (per joint and mass
            point, shape (n, J)) whose gravity torque decides the loaded flank of the backlash
            (the diagnosis's lumped-mass compliance fit), or None.
        conditions: what the data were measured under (payloads, tool points, temperature
            range, units, joint limits, instrument, data file hash; :mod:`.conditions`), or
            None (unknown: nothing can be enforced).
        widen: physical domains widened by the user (domain key -> upper bound,
            :mod:`zrp.gap.model.domains`), or None.
        backlash_lead: per joint, whether the approach leaves the load on the leading flank
            of its play (the diagnosis's profiled flank, eq. B1), or None (lagging everywhere).
        undetermined: the parameters the data did not determine, as
            ``name: held at nominal (...)`` / ``name: undetermined (...)``
            (:mod:`zrp.gap.search.determination`): an undetermined tool or base direction is
            flagged so in the files a controller reads.
        taken_out: the effects' values the diagnosis took out as non-physical (outside
            their physical domains, e.g. a negative compliance), in words: held at nominal.
        backlash_switch_weights: per joint, the plausible switching torques and their
            weights of the diagnosis's flank model (the loaded-flank share of a pose is their
            weighted vote), or None (``backlash_switch`` alone decides).
        learned: the learned residual term on the joint angles (:mod:`.learned`; its points
            are ``tool_labels``), or None (the physical model alone).
    """

    model: Manipulator
    nominal: Manipulator
    base_rotation: F64
    base_translation: F64
    tool_labels: tuple[str, ...]
    tool_points: F64
    joint_offsets: F64
    terms: tuple[Term, ...] = ()
    kappa: float = 0.0
    t_ref: float = 20.0
    backlash_switch: tuple[float | None, ...] | None = None
    payload_kg: float = 0.0
    gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0)
    harmonics: tuple[int, ...] = (1, 2)
    frame: str = "instrument"
    compliance_model: str = "lumped_masses"
    withheld_rms: float | None = None
    gravity_side_weights: F64 | None = None
    conditions: Conditions | None = None
    widen: dict[str, float] | None = None
    backlash_lead: tuple[bool, ...] | None = None
    undetermined: tuple[str, ...] = ()
    taken_out: tuple[str, ...] = ()
    backlash_switch_weights: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] | None = None
    learned: LearnedTerm | None = None

    def __post_init__(self) -> None:
        n = self.model.n
        if self.nominal.n != n:
            raise InputError(f"nominal: {self.nominal.n} joints, calibrated model {n}")
        rb = np.asarray(self.base_rotation, dtype=float)
        if rb.shape != (3, 3) or not np.allclose(rb @ rb.T, np.eye(3), atol=1e-9):
            raise InputError("base_rotation: expected a 3x3 rotation matrix")
        if np.shape(self.base_translation) != (3,):
            raise InputError("base_translation: expected shape (3,)")
        tp = np.asarray(self.tool_points, dtype=float)
        if tp.shape != (len(self.tool_labels), 3):
            raise InputError(f"tool_points: expected shape ({len(self.tool_labels)}, 3)")
        if np.shape(self.joint_offsets) != (n,):
            raise InputError(f"joint_offsets: expected shape ({n},)")
        if self.frame not in ("instrument", "base"):
            raise InputError(f"frame: expected 'instrument' or 'base', got {self.frame!r}")
        if self.conditions is not None and len(self.conditions.joint_limits) != n:
            raise InputError(f"conditions.joint_limits: {len(self.conditions.joint_limits)} "
                             f"entries for {n} joints")
        if self.backlash_lead is not None and len(self.backlash_lead) != n:
            raise InputError(f"backlash_lead: {len(self.backlash_lead)} flags for {n} joints")
        check_learned(self.learned, tuple(self.tool_labels), n)
        bad = [t.name for t in self.terms if not 1 <= t.joint <= n]
        if bad:
            raise InputError(f"terms {bad}: joint outside 1..{n}")

    @property
    def n(self) -> int:
        return self.model.n

    # ---- from a diagnosis -----------------------------------------------------------------
    @classmethod
    def from_diagnosis(cls, diag: Diagnosis, registration_only: bool = False,
                       fit: FitResult | None = None) -> CalibratedRobot:
        """The calibrated robot of the final model of ``diag`` (its jointly estimated
        parameters, registration included); with ``registration_only``, the nominal model
        with the registration alone (base frame and tool points: the usual baseline); with
        ``fit``, another estimate of the final model's parameters (e.g. the full-pose refit
        of :func:`zrp.calibration.fullpose.full_pose_calibration`)."""
        if fit is None:
            fit = diag.nominal_fit if registration_only else diag.final_fit
        rec = final_model_record(diag, registration_only=registration_only, fit=fit)
        return cls.from_record(rec, diag.context.model, Conditions.from_measurements(
            diag.context.meas, diag.context.model))

    @classmethod
    def from_record(cls, rec: FinalModelRecord, nominal: Manipulator,
                    conditions: Conditions | None = None, widen: dict[str, float] | None = None
                    ) -> CalibratedRobot:
        """The calibrated robot of a diagnosis's final-model record
        (:class:`zrp.gap.FinalModelRecord`, stored in diagnosis.json): its revolute offsets
        folded into its geometry (module doc), on the ``nominal`` model the diagnosis started
        from, with the data's ``conditions`` and the widened domains (every value of the
        record checked in its domain on ``nominal`` first: RecordDomainError)."""
        rec.check_domains(nominal)
        delta, terms, kappa = _joint_terms(rec, nominal)
        folded, tools_f = _fold(nominal, rec.axes, rec.bodies, delta, rec.tool_offsets)
        return cls(
            model=folded, nominal=nominal, base_rotation=rec.base_rotation,
            base_translation=rec.base_translation, tool_labels=rec.tool_labels,
            tool_points=tools_f, joint_offsets=delta, terms=tuple(terms), kappa=kappa,
            t_ref=rec.t_ref_degC, backlash_switch=rec.backlash_switch,
            payload_kg=rec.payload_kg, gravity_dir=rec.gravity_dir, harmonics=rec.harmonics,
            frame=rec.frame, compliance_model=rec.compliance_model,
            withheld_rms=rec.withheld_rms, gravity_side_weights=rec.gravity_side_weights,
            conditions=conditions, widen=widen, backlash_lead=rec.backlash_lead,
            undetermined=rec.undetermined, taken_out=rec.taken_out,
            backlash_switch_weights=rec.backlash_switch_weights)

    @classmethod
    def from_corrections(cls, nominal: Manipulator, joint_offsets: ArrayLike,
                         axes: ArrayLike | None = None, bodies: ArrayLike | None = None
                         ) -> CalibratedRobot:
        """A purely geometric calibrated robot (base frame, no tool points, no joint map):
        ``nominal`` with corrected axes (n, 3) and bodies (n + 1, 3) (default: the nominal's)
        and revolute joint offsets delta (n,) folded in (e.g. a simulated calibration)."""
        delta = np.asarray(joint_offsets, dtype=float)
        if delta.shape != (nominal.n,):
            raise InputError(f"joint_offsets: expected shape ({nominal.n},), got {delta.shape}")
        u = np.asarray(nominal.axes if axes is None else axes, dtype=float)
        b = np.asarray(nominal.bodies if bodies is None else bodies, dtype=float)
        if u.shape != (nominal.n, 3) or b.shape != (nominal.n + 1, 3):
            raise InputError(f"axes, bodies: expected shapes ({nominal.n}, 3) and "
                             f"({nominal.n + 1}, 3), got {u.shape} and {b.shape}")
        folded, tools = _fold(nominal, u / np.linalg.norm(u, axis=1, keepdims=True), b,
                              np.where(nominal.prismatic, 0.0, delta), np.zeros((0, 3)))
        return cls(folded, nominal, np.eye(3), np.zeros(3), (), tools,
                   np.where(nominal.prismatic, 0.0, delta), frame="base")

    def fold_rotations(self) -> F64:
        """R_k(delta) per joint, shape (n, 3, 3): the rotation the folded offsets of joints
        1..k give everything after joint k (identity without offsets); the identified axes are
        u_k = R_{k-1}(delta)^T u'_k."""
        r = np.eye(3)
        out = np.empty((self.n, 3, 3))
        for k in range(self.n):
            u = r.T @ np.asarray(self.model.axes[k])
            if not self.model.prismatic[k]:
                r = r @ rotation_about(u, float(self.joint_offsets[k]))
            out[k] = r
        return out

    # ---- prediction -----------------------------------------------------------------------
    def context(self, q: ArrayLike, cond: PoseConditions | None = None) -> Context:
        """The diagnosis's :class:`~zrp.gap.Context` on commanded joint values q (P, n)."""
        cond = cond or PoseConditions()
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if q.ndim != 2 or q.shape[1] != self.n:
            raise InputError(f"q: expected shape (P, {self.n}), got {np.shape(q)}")
        P = q.shape[0]
        meas = Measurements.from_arrays(np.arange(P), q, np.zeros((P, 3)), frame=self.frame,
                                        temp=cond.temp, load=cond.load,
                                        direction=cond.direction, source="targets")
        sw = None if self.backlash_switch is None else tuple(
            np.inf if v is None else float(v) for v in self.backlash_switch)
        tau = None if cond.gravity_torque is None else np.asarray(cond.gravity_torque,
                                                                  dtype=float)
        ctx = Context(self.nominal, meas, tau, self.gravity_dir, self.harmonics, self.t_ref,
                      backlash_switch=sw, payload_kg=self.payload_kg,
                      backlash_lead=self.backlash_lead,
                      backlash_switch_weights=self.backlash_switch_weights)
        if tau is None and self.gravity_side_weights is not None:
            _, h = ctx.moment_arms()
            side = np.einsum("pkj,kj->pk", h, np.asarray(self.gravity_side_weights))
            ctx = dataclasses.replace(ctx, gravity_side=side)
        return ctx

    def actual_joint_values(self, q: ArrayLike, cond: PoseConditions | None = None) -> F64:
        """x = q + dq: the joint values of the calibrated geometry the robot reaches when q is
        commanded, shape (P, n)."""
        ctx = self.context(q, cond)
        return ctx.q + joint_correction(self.terms, ctx)

    def body_scale(self, P: int, temp: ArrayLike | None) -> F64:
        """1 + kappa (temp - t_ref) per pose, shape (P,)."""
        if temp is None or self.kappa == 0.0:
            return np.ones(P)
        return 1.0 + self.kappa * (np.asarray(temp, dtype=float) - self.t_ref)

    def predict(self, q: ArrayLike, point: str | None = None,
                cond: PoseConditions | None = None, frame: str = "instrument") -> F64:
        """Predicted position of a tool point (None: the model's end point) when q (P, n) is
        commanded, shape (P, 3), in the instrument frame (or ``frame="base"``)."""
        cond = cond or PoseConditions()
        x = self.actual_joint_values(q, cond)
        pos, rn, _, _ = chain(self.model, x, self.body_scale(len(x), cond.temp))
        tool = self.tool_offset(point)
        y, _ = correct_hand(self.learned, self.base_rotation, self.tool_points,
                            np.atleast_2d(np.asarray(q, dtype=float)), pos + rn @ tool, rn, tool)
        return self.to_frame(y, frame)

    def predict_rotation(self, q: ArrayLike, cond: PoseConditions | None = None,
                         frame: str = "instrument") -> F64:
        """Predicted hand rotation R'_n(x) when q (P, n) is commanded, shape (P, 3, 3), in the
        instrument frame (R_b R'_n) or ``frame="base"``."""
        x = self.actual_joint_values(q, cond or PoseConditions())
        pos, rn, _, _ = chain(self.model, x)
        _, rn = correct_hand(self.learned, self.base_rotation, self.tool_points,
                             np.atleast_2d(np.asarray(q, dtype=float)), pos, rn, np.zeros(3))
        if frame == "base":
            return rn
        if frame != "instrument":
            raise InputError(f"frame: expected 'instrument' or 'base', got {frame!r}")
        return np.asarray(self.base_rotation) @ rn

    def tool_offset(self, point: str | None) -> F64:
        """t'_j of the tool point ``point`` (zeros for None), shape (3,)."""
        if point is None:
            return np.zeros(3)
        if point not in self.tool_labels:
            raise InputError(f"point: {point!r} is not a tool point; known: "
                             f"{', '.join(self.tool_labels)}")
        return np.asarray(self.tool_points[self.tool_labels.index(point)], dtype=float)

    def to_frame(self, y: F64, frame: str) -> F64:
        """Base-frame positions (..., 3) in ``frame`` ("instrument" or "base")."""
        if frame == "base":
            return y
        if frame != "instrument":
            raise InputError(f"frame: expected 'instrument' or 'base', got {frame!r}")
        return y @ np.asarray(self.base_rotation).T + np.asarray(self.base_translation)


def _fold(model: Manipulator, u: F64, bodies: F64, delta: F64, tools: F64
          ) -> tuple[Manipulator, F64]:
    """The corrected geometry (axes u (n, 3), bodies (n + 1, 3)) with the revolute offsets
    delta (n,) folded in, and the tool offsets t (M, 3) rotated alike (see the module doc)."""
    n = model.n
    r = np.eye(3)
    axes = np.empty((n, 3))
    new_b = np.empty((n + 1, 3))
    for k in range(n + 1):
        new_b[k] = r @ bodies[k]
        if k == n:
            break
        axes[k] = r @ u[k]
        if not model.prismatic[k]:
            r = r @ _rot(u[k], np.array([delta[k]]))[0]
    ee = model.end_effector
    folded = Manipulator.from_arrays(
        axes / np.linalg.norm(axes, axis=1, keepdims=True), new_b, axial=r @ ee.axial,
        transverse=r @ ee.transverse, types=model.joint_types,
        name=f"{model.name} (calibrated)", length_unit=model.length_unit,
        joint_names=[j.name for j in model.joints], limits=[j.limits for j in model.joints],
        velocity_limits=[j.velocity_limit for j in model.joints])
    return folded, tools @ r.T
