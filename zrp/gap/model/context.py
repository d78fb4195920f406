"""The hub of the diagnosis: the parameters of a corrected model (:class:`ParamSpec`) and
everything the effects need about the data (:class:`Context`), with the names of the effects.

How each kind of parameter enters the corrected model is listed in
:mod:`zrp.gap.model.effects`; :mod:`zrp.gap.model.problem` evaluates it with its analytic
Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError, UnitError
from zrp.gap.data.measurements import Measurements
from zrp.gap.model.choices import EFFECTS, REGISTRATION
from zrp.gap.model.domains import DEFAULT_MAX_TILT_RAD
from zrp.kinematics.forward import forward_kinematics
from zrp.kinematics.identification import axis_tangents
from zrp.model.manipulator import Manipulator
from zrp.units import G_STANDARD, angle_bounds, metres_per_unit

__all__ = [
    "EFFECTS",
    "KINDS",
    "MIN_EXCITATION_RAD",
    "REGISTRATION",
    "Context",
    "OrientationWeights",
    "ParamSpec",
]


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
class OrientationWeights:
    """How the measured orientations enter a fit beside the positions.

    Attributes:
        sigma_position: position noise per coordinate (length unit), the weight of the
            position block.
        sigma_orientation: orientation noise per component (rad), the weight of the
            orientation block.
        probe_rotation: R_t0, the starting probe rotation (3, 3); each fit refines it by a
            rotation vector psi (eq. O1).
        source: how sigma_orientation was obtained ("given" or "estimated").
    """

    sigma_position: float
    sigma_orientation: float
    probe_rotation: F64
    source: str = "estimated"

    def __post_init__(self) -> None:
        for name in ("sigma_position", "sigma_orientation"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"OrientationWeights.{name}: expected a positive number, "
                                 f"got {v!r}")
        if np.shape(self.probe_rotation) != (3, 3):
            raise InputError("OrientationWeights.probe_rotation: expected shape (3, 3)")


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
        backlash_lead: per joint, whether a joint the approach decides rests on the leading
            flank of its play (True: the load's inertia carries it onto the front flank as the
            motor stops, eq. B1) instead of lagging behind the motor (False, the default:
            the load's friction holds it back). None: lagging everywhere.
        payload_kg: a payload at the tool that the MJCF torques lack, kg (added to them for
            the backlash flank; the diagnosis profiles it).
        max_tilt_rad: the largest axis tilt a fit may accept (the domain of
            ``axis_misalignment``, :mod:`zrp.gap.model.domains`).
        orientation: with measured orientations, how they weigh in every fit
            (:func:`zrp.gap.fit.leastsq.fit`); None: positions only.
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
    backlash_lead: tuple[bool, ...] | None = None
    payload_kg: float = 0.0
    max_tilt_rad: float = DEFAULT_MAX_TILT_RAD
    orientation: OrientationWeights | None = None

    def __post_init__(self) -> None:
        if self.meas.n_joints != self.model.n:
            raise InputError(f"measurements have {self.meas.n_joints} joint columns but the model "
                             f"{self.model.name!r} has {self.model.n} joints")
        self._check_radians()
        g = np.asarray(self.gravity_dir, dtype=float)
        if g.shape != (3,) or not np.isclose(np.linalg.norm(g), 1.0):
            raise InputError(f"gravity_dir: expected a unit 3-vector, got {self.gravity_dir}")
        if self.gravity_torque is not None and np.shape(self.gravity_torque) != (
                len(self.meas.pose_ids), self.model.n):
            raise InputError(f"gravity_torque: expected shape ({len(self.meas.pose_ids)}, "
                             f"{self.model.n}), got {np.shape(self.gravity_torque)}")
        if not self.harmonics or any(int(h) < 1 for h in self.harmonics):
            raise InputError(f"harmonics: expected positive integers, got {self.harmonics}")
        if self.backlash_lead is not None and len(self.backlash_lead) != self.model.n:
            raise InputError(f"backlash_lead: expected {self.model.n} flags (one per joint), "
                             f"got {len(self.backlash_lead)}")

    def _check_radians(self) -> None:
        """Degrees passed as rad (``Measurements.from_arrays`` takes rad): a revolute joint
        value beyond one turn, or beyond the joint's limit where that reaches further, cannot
        be an angle in rad (the rule of the CSV reader, :func:`zrp.units.joint_values_to_rad`).
        """
        rev = ~np.asarray(self.model.prismatic, dtype=bool)
        bound = np.maximum(angle_bounds(self.model.lower, self.model.upper), 2.0 * np.pi)
        big = rev[None, :] & (np.abs(self.meas.q) > bound[None, :] + 1e-9)
        if big.any():
            i, k = (int(v) for v in np.argwhere(big)[0])
            raise UnitError(f"{self.meas.source} row {i + 1}: joint {k + 1} "
                            f"({self.model.joint_names[k]}) is {self.meas.q[i, k]:g}, beyond "
                            f"{bound[k]:.4g} rad (one turn, or the joint's limit): it cannot be "
                            "an angle in rad and looks like degrees; the measurements take q "
                            "in rad (convert with np.radians)")

    @property
    def n(self) -> int:
        return self.model.n

    @cached_property
    def q(self) -> F64:
        """Joint values per pose, shape (P, n)."""
        return self.meas.q_pose

    def q_of(self, poses: NDArray[np.int64]) -> F64:
        """Joint values of the given poses, shape (len(poses), n) (``q[poses]``; a subclass
        may compute them for those poses only, without holding q of every pose)."""
        return self.q[poses]

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
        unit play (eq. B1): where |gravity torque| <= the joint's :attr:`backlash_switch`, the
        approach decides, -d (lagging) or +d (leading, :attr:`backlash_lead`) for approach
        direction d; above it the sign of the gravity torque; with
        :attr:`backlash_switch_weights`, the weighted mean over the plausible switches."""
        d = self.meas.approach_direction() * self.approach_flank()[None, :]
        tau = self.gravity_side_torque()
        sw = (np.full(self.n, np.inf) if self.backlash_switch is None
              else np.asarray(self.backlash_switch, dtype=float))
        out = np.where(np.abs(tau) > sw, np.sign(tau), d)
        if self.backlash_switch_weights is not None:
            for k, (thr, w) in enumerate(self.backlash_switch_weights):
                t = np.asarray(thr, dtype=float)
                p_g = (np.abs(tau[:, k])[:, None] > t[None, :]) @ np.asarray(w, dtype=float)
                out[:, k] = p_g * np.sign(tau[:, k]) + (1.0 - p_g) * d[:, k]
        return out

    def approach_flank(self) -> F64:
        """Per joint, the side of its play a joint the approach decides rests on, per unit
        approach direction, shape (n,): -1 lagging, +1 leading (:attr:`backlash_lead`)."""
        if self.backlash_lead is None:
            return -np.ones(self.n)
        return np.where(np.asarray(self.backlash_lead, dtype=bool), 1.0, -1.0)

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
        points not beyond joint k are 0. Computed once per context (every candidate effect and
        step asks for them): h is read-only.
        """
        labels, h = self._lumped_arms
        return list(labels), h

    @cached_property
    def _lumped_arms(self) -> tuple[tuple[str, ...], F64]:
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
        h.setflags(write=False)
        return tuple(labels), h
