"""Measurement planning: which poses to measure so that the chosen effects are identifiable.

Criterion: D-optimality of the identification Jacobian of the gap diagnosis's corrected model
(:class:`zrp.gap.model.problem.Problem`: registration + the chosen effects, evaluated at the nominal
parameters), i.e. maximise log det(J^T J) over N poses drawn from a candidate set (uniform in
the joint limits, within the model's own, above a floor keep-out). Selection: DETMAX-style
exchange (Mitchell 1974):
from a random start, add the candidate that raises log det most, then drop the design pose
whose removal lowers it least, until the pose added is the one dropped. With A_i the rows of
pose i (3 per tool point) and M = J^T J (Eq: matrix determinant lemma)

    gain(i) = log det(I + A_i M^-1 A_i^T),   loss(i) = -log det(I - A_i M^-1 A_i^T).

Before anything is measured, the predicted standard deviation of each parameter is
sigma sqrt(diag(M^-1)) (sigma: the instrument's noise per coordinate). Parameters that even the
whole candidate set cannot separate from the others (e.g. q1.offset from base.rz) are
reported as unidentifiable and left out. Backlash needs both approach directions: every
candidate gets a random approach direction per joint (written with the plan, ``dir`` columns);
compliance uses the lumped-mass moment arms (or MJCF torques given per candidate). Thermal
expansion cannot be planned from poses (it needs a temperature spread) and is refused.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arguments import check_float
from zrp.arrays import F64
from zrp.errors import InputError, ZRPWarning
from zrp.gap.data.measurements import Measurements
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.model.problem import Problem
from zrp.kinematics.forward import forward_kinematics
from zrp.kinematics.sampling import default_limits, uniform_joint_values
from zrp.model.manipulator import Manipulator
from zrp.units import TRACKER_NOISE_MM, units_per_mm

__all__ = ["Plan", "PlanWarning", "design_std", "plan_poses"]

#: A parameter is aliased when less than this fraction of its column stays after projection on
#: the columns before it: its predicted std would be inflated more than 1 / ALIAS_TOL times by
#: the others (the variance inflation of a near-alias). 1e-3, not the fit's 1e-6: a URDF's
#: rounded angles (rpy 1.5708 for pi/2, 3.7e-6 rad off) leave exact aliases 1e-6 apart, which
#: planned as independent printed stds of 1e3 mm (xArm7's b2.y..b5.y).
ALIAS_TOL = 1e-3


class PlanWarning(ZRPWarning):
    """A parameter stays unidentifiable, or the plan is poorly conditioned."""


@dataclass(frozen=True, eq=False)
class Plan:
    """N planned poses and what they are predicted to identify.

    Attributes:
        q: the poses, rad, shape (N, n), in measurement order.
        direction: approach direction per pose and joint (-1/+1), shape (N, n).
        names: parameters identified (registration first), (p,).
        std: predicted standard deviation of each, shape (p,) (their units).
        units: their units (p,).
        unidentifiable: parameters no candidate set could separate (left out).
        log_det: log det(J^T J / N) of the plan (columns scaled to unit norm on the candidates).
        log_det_random: the same for N random candidates (the first start), for comparison.
    """

    q: F64
    direction: F64
    names: tuple[str, ...]
    std: F64
    units: tuple[str, ...]
    unidentifiable: tuple[str, ...]
    log_det: float
    log_det_random: float

    def __post_init__(self) -> None:
        if self.std.shape != (len(self.names),):
            raise InputError("Plan: std does not match names")

    def predicted_std(self, name: str) -> float:
        if name not in self.names:
            raise InputError(f"name: {name!r} is not a planned parameter")
        return float(self.std[self.names.index(name)])


def _candidates(model: Manipulator, count: int, rng: np.random.Generator, limits: F64,
                tool: F64, floor_z: float | None, n_poses: int) -> F64:
    if count < n_poses:
        raise InputError(f"candidates: {count} candidate poses cannot give {n_poses} distinct "
                         f"poses; draw at least {n_poses}, or many more (default 1000) for a "
                         "good plan")
    q = uniform_joint_values(model, count, rng, limits)
    if floor_z is None:
        return q
    fk = forward_kinematics(model, q)
    pts = np.concatenate([fk.points, fk.position[:, None, :],
                          fk.position[:, None, :] + np.einsum("sij,mj->smi", fk.rotation,
                                                              tool)], axis=1)
    keep = pts[..., 2].min(axis=1) > floor_z
    if keep.sum() < 2 * model.n:
        raise InputError(f"floor_z: only {int(keep.sum())} of {count} candidate poses keep "
                         f"the arm above z = {floor_z}")
    if keep.sum() < n_poses:
        raise InputError(f"floor_z: only {int(keep.sum())} of {count} candidate poses keep "
                         f"the arm above z = {floor_z}, fewer than the {n_poses} poses asked; "
                         "draw more candidates")
    return q[keep]


def _jacobian(model: Manipulator, q: F64, direction: F64, tool: F64, effects: Sequence[str],
              gravity_torque: F64 | None) -> tuple[list[ParamSpec], F64]:
    """Jacobian (C, 3M, p) of registration + effects at the nominal parameters."""
    C, M = len(q), len(tool)
    labels = [f"s{j + 1}" for j in range(M)]
    meas = Measurements.from_arrays(np.repeat(np.arange(C), M), np.repeat(q, M, axis=0),
                                    np.zeros((C * M, 3)), point=np.tile(labels, C),
                                    direction=np.repeat(direction, M, axis=0), source="plan")
    ctx = Context(model, meas, gravity_torque)
    specs = registration_parameters(ctx)
    for e in effects:
        if e == "thermal_expansion":
            raise InputError("effects: thermal_expansion needs a temperature spread, not "
                             "poses; plan the others and measure while the robot warms up")
        es, why = effect_parameters(ctx, e)
        if why:
            warnings.warn(f"{e}: {why}", PlanWarning, stacklevel=3)
        specs += es
    prob = Problem(ctx, specs, np.arange(C))
    theta = np.zeros(len(specs))
    for i, s in enumerate(specs):
        if s.kind == "tool":
            theta[i] = tool[s.comp // 3, s.comp % 3]
    _, J = prob.evaluate(theta)
    return specs, J.reshape(C, M * 3, len(specs))


#: A column is numerically zero below this fraction of the largest column of its unit (a
#: parameter that moves no point: q6.offset with the tool point on joint 6's axis).
ZERO_TOL = 1e-8


def _identifiable(J: F64, units: Sequence[str]) -> NDArray[np.bool_]:
    """Columns of J (R, p) that are not numerically zero (:data:`ZERO_TOL` of the largest
    column in the same unit: normalising rounding noise would make it look independent) and
    keep > ALIAS_TOL of their norm after projection on the columns kept before them
    (Gram-Schmidt in column order)."""
    norm = np.linalg.norm(J, axis=0)
    scale = np.array([max(norm[[i for i, v in enumerate(units) if v == u]]) for u in units])
    live = norm > ZERO_TOL * scale
    A = J / np.maximum(norm, 1e-300)
    keep = np.zeros(A.shape[1], dtype=bool)
    Q = np.zeros((A.shape[0], 0))
    for j in range(A.shape[1]):
        if not live[j]:
            continue
        r = A[:, j] - Q @ (Q.T @ A[:, j])
        r -= Q @ (Q.T @ r)
        nr = np.linalg.norm(r)
        if nr > ALIAS_TOL:
            keep[j] = True
            Q = np.column_stack([Q, r / nr])
    return keep


def _logdet(A: F64, design: NDArray[np.int64]) -> float:
    M = np.einsum("skp,skq->pq", A[design], A[design])
    sign, ld = np.linalg.slogdet(M)
    return float(ld) if sign > 0 else -np.inf


def _exchange(A: F64, design: NDArray[np.int64], max_iter: int) -> NDArray[np.int64]:
    """DETMAX-style exchange (module doc) on per-pose row blocks A (C, k, p)."""
    design = design.copy()
    k = A.shape[1]
    eye = np.eye(k)
    for _ in range(max_iter):
        Mi = np.linalg.inv(np.einsum("skp,skq->pq", A[design], A[design]))
        G = (A @ Mi) @ A.transpose(0, 2, 1)      # (C, k, k); a 3-operand einsum is 100x slower
        gain = np.linalg.slogdet(eye + G)[1]
        gain[design] = -np.inf
        add = int(np.argmax(gain))
        trial = np.append(design, add)
        Mi = np.linalg.inv(np.einsum("skp,skq->pq", A[trial], A[trial]))
        At = A[trial]
        Gd = (At @ Mi) @ At.transpose(0, 2, 1)
        sign, ld = np.linalg.slogdet(eye - Gd)
        loss = np.where(sign > 0, -ld, np.inf)
        drop = int(np.argmin(loss))
        if drop == len(design):
            break
        design = np.delete(trial, drop)
    return design


def plan_poses(model: Manipulator, n_poses: int, effects: Sequence[str], *,
               rng: np.random.Generator, limits: ArrayLike | None = None,
               tool_points: ArrayLike = ((0.0, 0.0, 0.0),), floor_z: float | None = None,
               noise_sigma: float | None = None, candidates: int = 1000,
               max_iter: int = 300,
               gravity_torque_fn: object = None, direction_fn: object = None) -> Plan:
    """Choose ``n_poses`` poses that identify registration + ``effects`` (module doc).

    Args:
        model: the nominal model.
        n_poses: poses to measure (N).
        effects: effects to identify (of :data:`zrp.gap.EFFECTS`, not thermal_expansion).
        rng: draws the candidates, their approach directions and the start.
        limits: joint limits, shape (n, 2), within the model's own (default
            :func:`zrp.kinematics.sampling.default_limits`: +-2.5 rad within the model's
            limits, slides within theirs).
        tool_points: tool offsets t_j (zero-reference base frame, length unit), shape (M, 3).
        floor_z: candidates with any joint point or tool point below this z (base frame) are
            excluded (None: no keep-out).
        noise_sigma: instrument noise per coordinate (length unit) for the predicted std;
            None: a laser tracker's :data:`~zrp.units.TRACKER_NOISE_MM` in the model's unit.
        candidates: size of the candidate set.
        gravity_torque_fn: optional q (C, n) -> MJCF gravity torques (C, n) (N m).
        direction_fn: optional q (C, n) -> approach directions (C, n) in {-1, 0, +1} that the
            measuring procedure imposes (e.g. lifting the gravity-loaded joints); 0 leaves the
            joint's direction to the plan (drawn at random per candidate).

    Raises:
        InputError: too few poses for the parameters, limits beyond the model's (naming the
            joint), invalid arguments.
    """
    tool = np.atleast_2d(np.asarray(tool_points, dtype=float))
    lim = _within_model(model, limits)
    q = _candidates(model, candidates, rng, lim, tool, floor_z, n_poses)
    d = rng.choice([-1.0, 1.0], size=q.shape)
    if direction_fn is not None:
        imposed = np.asarray(direction_fn(q), dtype=float)  # type: ignore[operator]
        if imposed.shape != q.shape or not np.all(np.isin(imposed, (-1.0, 0.0, 1.0))):
            raise InputError(f"direction_fn: expected -1/0/+1 of shape {q.shape}, got "
                             f"shape {imposed.shape}")
        d = np.where(imposed != 0.0, imposed, d)
    tau = None if gravity_torque_fn is None else np.asarray(gravity_torque_fn(q))  # type: ignore[operator]
    specs, J = _jacobian(model, q, d, tool, effects, tau)
    keep = _identifiable(J.reshape(-1, len(specs)), [s.unit for s in specs])
    lost = tuple(s.name for s, k in zip(specs, keep, strict=True) if not k)
    if lost:
        warnings.warn(f"{len(lost)} parameter(s) stay unidentifiable with any of these poses "
                      f"(aliased with others, or moving no measured point) and are left out: "
                      f"{', '.join(lost)}",
                      PlanWarning, stacklevel=2)
    specs = [s for s, k in zip(specs, keep, strict=True) if k]
    J = J[:, :, keep]
    p = len(specs)
    if n_poses * J.shape[1] <= p:
        raise InputError(f"n_poses: {n_poses} poses give {n_poses * J.shape[1]} coordinates, "
                         f"not enough for {p} parameters")
    scale = np.linalg.norm(J.reshape(-1, p), axis=0) / np.sqrt(len(q))
    A = J / scale
    start = rng.choice(len(q), size=n_poses, replace=False)
    design = _exchange(A, start, max_iter)
    Mi = np.linalg.inv(np.einsum("skp,skq->pq", J[design], J[design]))
    std = _noise(model, noise_sigma) * np.sqrt(np.diag(Mi))
    order = np.sort(design)
    return Plan(q[order], d[order], tuple(s.name for s in specs), std,
                tuple(s.unit for s in specs), lost,
                _logdet(A, design) - p * np.log(n_poses), _logdet(A, start) - p * np.log(n_poses))


def design_std(model: Manipulator, q: ArrayLike, direction: ArrayLike, effects: Sequence[str], *,
               tool_points: ArrayLike = ((0.0, 0.0, 0.0),), noise_sigma: float | None = None,
               gravity_torque: ArrayLike | None = None) -> tuple[tuple[str, ...], F64]:
    """Predicted standard deviation of registration + ``effects`` for a given design (any
    poses, e.g. random ones, to set beside a plan): sigma sqrt(diag((J^T J)^-1)) over the
    parameters the design separates (aliased ones left out, as in :func:`plan_poses`).

    Args:
        q: the poses, rad, shape (N, n); direction: approach directions (N, n), -1/0/+1.
        gravity_torque: MJCF gravity torques at q (N, n), N m, or None (lumped masses).
        noise_sigma: instrument noise per coordinate (length unit); None: a laser tracker's
            :data:`~zrp.units.TRACKER_NOISE_MM` in the model's unit.

    Returns:
        the parameter names (p,) and their standard deviations (p,) (their units).
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    da = np.asarray(direction, dtype=float)
    if qa.ndim != 2 or qa.shape[1] != model.n or da.shape != qa.shape:
        raise InputError(f"q, direction: expected two arrays of shape (N, {model.n}), got "
                         f"{qa.shape} and {da.shape}")
    tool = np.atleast_2d(np.asarray(tool_points, dtype=float))
    tau = None if gravity_torque is None else np.asarray(gravity_torque, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanWarning)
        specs, J = _jacobian(model, qa, da, tool, effects, tau)
    J = J.reshape(-1, len(specs))
    keep = _identifiable(J, [s.unit for s in specs])
    Jk = J[:, keep] / np.linalg.norm(J[:, keep], axis=0)
    Mi = np.linalg.inv(Jk.T @ Jk) / np.outer(*(2 * [np.linalg.norm(J[:, keep], axis=0)]))
    names = tuple(s.name for s, k in zip(specs, keep, strict=True) if k)
    return names, _noise(model, noise_sigma) * np.sqrt(np.diag(Mi))


def _within_model(model: Manipulator, limits: ArrayLike | None) -> F64:
    """The planning limits: ``limits`` checked against the model's own, or its defaults."""
    if limits is None:
        return default_limits(model)
    lim = np.asarray(limits, dtype=float)
    if lim.shape != (model.n, 2):
        raise InputError(f"limits: expected shape ({model.n}, 2), got {lim.shape}")
    out = (lim[:, 0] < model.lower - 1e-12) | (lim[:, 1] > model.upper + 1e-12)
    if out.any():
        k = int(np.argmax(out))
        raise InputError(f"limits: joint {k + 1} ({model.joint_names[k]}) planned over "
                         f"[{lim[k, 0]:.6g}, {lim[k, 1]:.6g}], beyond the model's limits "
                         f"[{model.lower[k]:.6g}, {model.upper[k]:.6g}] (rad or length unit)")
    return lim


def _noise(model: Manipulator, noise_sigma: float | None) -> float:
    """``noise_sigma`` checked, or a laser tracker's noise in the model's unit (None)."""
    if noise_sigma is None:
        return TRACKER_NOISE_MM * units_per_mm(model.length_unit, "model.length_unit")
    return check_float(noise_sigma, "noise_sigma", 0.0, unit=model.length_unit)
