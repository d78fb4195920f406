"""The learned residual term of a calibration: what the physical model leaves, as a smooth
function of the commanded joint angles (issue 36).

When ``zrp diagnose --residual-model`` keeps its learned term (kernel ridge regression of the
final physical model's residual on the joint angles, kept only when it lowers the withheld
error clearly: :mod:`zrp.gap.analysis.residual`), ``zrp calibrate --residual-model`` writes it
into ``compensation.json`` as the separate entry ``learned_residual`` (:meth:`LearnedTerm.
to_dict`): plain arrays, no pickle, enough to evaluate it exactly without scikit-learn.

Evaluation (eq. L1), for commanded joint values q (T, n):

    z_c   = (sin q_k, cos q_k) per revolute input joint k, q_k per prismatic one   (D columns)
    x     = (z - center) / scale * ard                                              (D,)
    g(q)  = mean + sum_i coef_i exp(-gamma |x - train_i|^2)                         (3M,)
    f_j(q) = frame R(turn_axis, q_1) g_j(q)                                         (per point)

``f`` is, per measured point j (``points`` order), the physical model's predicted minus
measured position (x, y, z; the calibration's ``frame``, length unit): the point is
**predicted at p_j(q) - f_j(q)**. ``g`` is learned in the arm's frame: the data's frame turned
with joint 1 (``frame``, data-from-base rotation, times the rotation by q_1 about joint 1's
nominal axis ``turn_axis`` in the base frame; no turn when ``turn_axis`` is null: a prismatic
joint 1; :mod:`zrp.gap.analysis.residual`). ``train`` (N, D) are the training poses' inputs already
scaled and multiplied by ``ard`` (1 / the per-column length scales), ``coef`` (N, 3M) the dual
coefficients of the ridge.

Compensation (:func:`hand_correction`) moves the whole hand: the per-point displacements
-f_j are fitted by a small rigid motion of the hand, d + w x r_j (r_j: point j from the end
point), by least squares over the points (three or more; with one or two points: the mean
translation, no rotation). The end point moves by d and the hand frame rotates by w.

Conditions: the term is valid within its **training ranges** (per input joint, the smallest
and largest commanded value it was trained on); :func:`learned_outside` flags commands beyond
them by more than :data:`~zrp.calibration.guards.RANGE_SHARE` of the range, which ``zrp
compensate`` refuses unless ``--accept-flagged``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.rotations.matrices import skew
from zrp.rotations.rodrigues import er_from_axis_angle, er_from_rotvec, matrix_from_er

__all__ = ["LearnedTerm", "check_learned", "correct_hand", "hand_correction", "learned_outside"]

#: what the term is, in the file (``learned_residual.kind``).
KIND = "kernel ridge regression (Gaussian RBF kernel) on (sin q, cos q) of the joint angles"
EVALUATE = ("x = (z - center) / scale * ard with z = (sin q_k, cos q_k) per revolute input "
            "joint (q_k if prismatic); g = mean + sum_i coef_i exp(-gamma |x - train_i|^2); "
            "f_j = frame R(turn_axis, q1) g_j (rotation by q1 about turn_axis; none if null); "
            "point j (points order, x, y, z in the data's frame) is predicted at p_j(q) - f_j")


@dataclass(frozen=True, eq=False)
class LearnedTerm:
    """A learned residual term (module docstring, eq. L1).

    Attributes:
        inputs: input joints, "q1".."qn"; widths: 2 (revolute: sin, cos) or 1 (prismatic).
        center, scale, ard: per column (D,): centre, spread, 1 / length scale.
        gamma: RBF width; train: (N, D) scaled training inputs; coef: (N, 3M); mean: (3M,).
        points: the measured point labels (M), the order of the 3M outputs.
        training_ranges: per input joint, (lowest, highest) commanded value trained on (rad;
            length unit if prismatic).
        withheld_rms_physical, withheld_rms_hybrid: the diagnosis's withheld RMS of the
            physical model alone and with the term (length unit); paired_z: their paired z.
        n_poses: training poses (N).
        frame: data-from-base rotation (3, 3); turn_axis: joint 1's nominal axis (3,), or
            None (no turn): the arm's frame g is learned in (eq. L1).
    """

    inputs: tuple[str, ...]
    widths: tuple[int, ...]
    center: F64
    scale: F64
    ard: F64
    gamma: float
    train: F64
    coef: F64
    mean: F64
    points: tuple[str, ...]
    training_ranges: tuple[tuple[float, float], ...]
    withheld_rms_physical: float
    withheld_rms_hybrid: float
    paired_z: float
    n_poses: int
    frame: F64
    turn_axis: F64 | None

    def __post_init__(self) -> None:
        bad = _problems(self)
        if bad:
            raise InputError("learned_residual: " + "; ".join(bad))

    @classmethod
    def from_residual_model(cls, rm: Any) -> LearnedTerm:
        """The term of a kept :class:`zrp.gap.analysis.residual.ResidualModel`."""
        k, s = rm.kernel, rm.scaling
        if k is None or s is None:
            raise InputError("residual model: it carries no fitted kernel")
        return cls(tuple(s.names), tuple(s.widths), np.asarray(s.center, float),
                   np.asarray(s.scale, float), np.asarray(k.scale, float), float(k.gamma),
                   np.asarray(k.Xtr, float), np.asarray(k.coef, float),
                   np.asarray(k.mean, float), tuple(rm.points), tuple(s.ranges),
                   float(rm.withheld_rms_physical), float(rm.withheld_rms_hybrid),
                   float(rm.paired_z), int(rm.n_poses), np.asarray(rm.frame, float),
                   None if rm.turn_axis is None else np.asarray(rm.turn_axis, float))

    @property
    def joints(self) -> list[int]:
        """0-based joint index of each input."""
        return [int(n[1:]) - 1 for n in self.inputs]

    def evaluate(self, q: ArrayLike) -> F64:
        """f(q) per point: predicted minus measured of the physical model, shape (T, M, 3)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        cols = []
        for k, w in zip(self.joints, self.widths, strict=True):
            if q.ndim != 2 or q.shape[1] <= k:
                raise InputError(f"q: expected shape (T, >= {k + 1}), got {q.shape}")
            cols += [q[:, k]] if w == 1 else [np.sin(q[:, k]), np.cos(q[:, k])]
        x = (np.column_stack(cols) - self.center) / self.scale * self.ard
        d2 = (np.sum(x**2, axis=1)[:, None] + np.sum(self.train**2, axis=1)[None, :]
              - 2.0 * x @ self.train.T)
        g = self.mean + np.exp(-self.gamma * np.maximum(d2, 0.0)) @ self.coef
        rot = np.asarray(self.frame) if self.turn_axis is None else (
            np.asarray(self.frame) @ matrix_from_er(er_from_axis_angle(self.turn_axis, q[:, 0])))
        return np.einsum("ij,tmj->tmi" if rot.ndim == 2 else "tij,tmj->tmi", rot,
                         g.reshape(len(q), len(self.points), 3))

    def to_dict(self) -> dict[str, Any]:
        """The ``learned_residual`` entry of compensation.json."""
        return {"kind": KIND, "evaluate": EVALUATE, "inputs": list(self.inputs),
                "widths": list(self.widths), "center": self.center.tolist(),
                "scale": self.scale.tolist(), "ard": self.ard.tolist(), "gamma": self.gamma,
                "train": self.train.tolist(), "coef": self.coef.tolist(),
                "mean": self.mean.tolist(), "points": list(self.points),
                "training_ranges": {n: list(r) for n, r in zip(
                    self.inputs, self.training_ranges, strict=True)},
                "withheld_rms_physical": self.withheld_rms_physical,
                "withheld_rms_hybrid": self.withheld_rms_hybrid,
                "paired_z": self.paired_z, "n_poses": self.n_poses,
                "frame": np.asarray(self.frame).tolist(),
                "turn_axis": None if self.turn_axis is None else self.turn_axis.tolist()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], src: str) -> LearnedTerm:
        """Read the entry back; every field checked (finite, shapes, ranges ordered).

        Raises:
            InputError: naming ``src`` and the field.
        """
        where = f"{src}: learned_residual"
        if not isinstance(d, Mapping):
            raise InputError(f"{where}: expected an object")
        try:
            inputs = tuple(str(v) for v in d["inputs"])
            ranges = d["training_ranges"]
            return cls(inputs, tuple(_whole(v, where) for v in d["widths"]),
                       *(_array(d[k], f"{where}.{k}") for k in ("center", "scale", "ard")),
                       _number(d["gamma"], f"{where}.gamma"),
                       *(_array(d[k], f"{where}.{k}") for k in ("train", "coef", "mean")),
                       tuple(str(v) for v in d["points"]),
                       tuple(tuple(_number(v, f"{where}.training_ranges.{n}")
                                   for v in ranges[n]) for n in inputs),
                       *(_number(d[k], f"{where}.{k}") for k in (
                           "withheld_rms_physical", "withheld_rms_hybrid", "paired_z")),
                       _whole(d["n_poses"], where), _array(d["frame"], f"{where}.frame"),
                       None if d["turn_axis"] is None
                       else _array(d["turn_axis"], f"{where}.turn_axis"))
        except (KeyError, TypeError) as exc:
            raise InputError(f"{where}: missing or malformed field ({exc})") from None
        except InputError as exc:
            raise InputError(f"{src}: {exc}" if not str(exc).startswith(src) else str(exc)
                             ) from None

    def words(self, unit: str) -> str:
        """What the term adds, for a report."""
        return (f"learned residual term ({', '.join(self.inputs)}; {self.n_poses} training "
                f"poses): withheld RMS {self.withheld_rms_physical:.4g} {unit} (physical "
                f"model) -> {self.withheld_rms_hybrid:.4g} {unit} with it")


def _number(v: object, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{where}: {v!r}; expected a finite number")
    return float(v)


def _whole(v: object, where: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise InputError(f"{where}: {v!r}; expected a whole number")
    return v


def _array(v: object, where: str) -> F64:
    try:
        a = np.array(v, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected an array of numbers") from None
    if a.dtype != float or not np.all(np.isfinite(a)):
        raise InputError(f"{where}: expected finite numbers")
    return a


def _problems(t: LearnedTerm) -> list[str]:
    """Every field outside its domain (shapes, finite, ordered ranges)."""
    return _name_problems(t) + _shape_problems(t) + _value_problems(t) + _frame_problems(t)


def _joint_name(n: str) -> bool:
    return n.startswith("q") and n[1:].isdigit() and int(n[1:]) >= 1


def _name_problems(t: LearnedTerm) -> list[str]:
    out = []
    if not t.inputs or len(t.widths) != len(t.inputs) or not all(map(_joint_name, t.inputs)):
        out.append(f"inputs: {list(t.inputs)[:8]}; expected joint names q1.. (one width each)")
    if any(w not in (1, 2) for w in t.widths):
        out.append(f"widths: {list(t.widths)}; expected 1 (prismatic) or 2 (revolute)")
    if not t.points or len(set(t.points)) != len(t.points):
        out.append(f"points: {list(t.points)[:8]}; expected distinct labels")
    return out


def _shape_problems(t: LearnedTerm) -> list[str]:
    D, M = sum(t.widths), len(t.points)
    N = np.shape(t.train)[0] if np.ndim(t.train) == 2 else -1
    shapes = {"center": (D,), "scale": (D,), "ard": (D,), "train": (N, D), "coef": (N, 3 * M),
              "mean": (3 * M,)}
    out = [f"{name}: shape {np.shape(getattr(t, name))}; expected {want} finite values"
           for name, want in shapes.items() if not _finite_shape(getattr(t, name), want)]
    if N < 1 or t.n_poses != N:
        out.append(f"n_poses: {t.n_poses}; the training inputs have {N} rows")
    return out


def _finite_shape(a: object, shape: tuple[int, ...]) -> bool:
    arr = np.asarray(a)
    return arr.shape == shape and bool(np.all(np.isfinite(arr)))


def _ordered(r: tuple[float, ...]) -> bool:
    return len(r) == 2 and all(math.isfinite(v) for v in r) and r[0] <= r[1]


def _value_problems(t: LearnedTerm) -> list[str]:
    out = []
    if not (np.all(np.asarray(t.scale) > 0) and np.all(np.asarray(t.ard) > 0)):
        out.append("scale, ard: expected positive values")
    if not (math.isfinite(t.gamma) and t.gamma > 0):
        out.append(f"gamma: {t.gamma!r}; expected a finite value > 0")
    if len(t.training_ranges) != len(t.inputs) or not all(map(_ordered, t.training_ranges)):
        out.append("training_ranges: expected per input a finite, ordered [low, high]")
    rms = (t.withheld_rms_physical, t.withheld_rms_hybrid)
    if not all(math.isfinite(v) and v >= 0 for v in rms):
        out.append("withheld_rms_physical, withheld_rms_hybrid: expected finite values >= 0")
    return out


def _frame_problems(t: LearnedTerm) -> list[str]:
    out = []
    fr = np.asarray(t.frame)
    if not (_finite_shape(fr, (3, 3)) and np.allclose(fr @ fr.T, np.eye(3), atol=1e-6)
            and np.linalg.det(fr) > 0):
        out.append("frame: expected a 3x3 rotation")
    if t.turn_axis is not None and not (_finite_shape(t.turn_axis, (3,)) and abs(
            float(np.linalg.norm(t.turn_axis)) - 1.0) <= 1e-6):
        out.append("turn_axis: expected null or a unit vector of 3 values")
    return out


def check_learned(term: LearnedTerm | None, tool_labels: tuple[str, ...], n: int) -> None:
    """Refuse a term (None: nothing to check) whose points are not the robot's tool points
    (in order) or whose input joints it lacks (``n`` joints).

    Raises:
        InputError: naming the mismatch.
    """
    if term is None:
        return
    if term.points != tool_labels or max(term.joints) >= n:
        raise InputError(f"learned: its points {list(term.points)} and joints "
                         f"{list(term.inputs)} are not this robot's (tool points "
                         f"{list(tool_labels)}, {n} joints)")


def learned_outside(term: LearnedTerm, q: F64, share: float) -> NDArray[np.bool_]:
    """Per command and input joint, shape (T, inputs): the command lies outside the term's
    training range by more than ``share`` of the range's width."""
    out = np.zeros((q.shape[0], len(term.inputs)), dtype=bool)
    for i, (k, (lo, hi)) in enumerate(zip(term.joints, term.training_ranges, strict=True)):
        tol = share * (hi - lo)
        out[:, i] = (q[:, k] < lo - tol) | (q[:, k] > hi + tol)
    return out


def hand_correction(term: LearnedTerm, q: F64, r_points: F64, base_rotation: F64
                    ) -> tuple[F64, F64]:
    """The hand's rigid correction in the base frame at commands q (module docstring):
    (d, the end point's displacement, (T, 3); R_w, the hand's extra rotation, (T, 3, 3)).

    ``r_points``: the term's points from the end point, base frame, shape (T, M, 3)."""
    rb = np.asarray(base_rotation, dtype=float)
    disp = -term.evaluate(q) @ rb          # instrument -> base frame: R_b^T v, row-wise
    T, M = disp.shape[:2]
    if M < 3:
        return disp.mean(axis=1), np.broadcast_to(np.eye(3), (T, 3, 3)).copy()
    # d + w x r = d - [r]x w: per pose a (3M, 6) least-squares problem
    A = np.concatenate([np.broadcast_to(np.eye(3), (T, M, 3, 3)), -skew(r_points)], axis=3)
    sol = np.einsum("tij,tj->ti", np.linalg.pinv(A.reshape(T, 3 * M, 6), rcond=1e-9),
                    disp.reshape(T, 3 * M))
    return sol[:, :3], matrix_from_er(er_from_rotvec(sol[:, 3:]))


def correct_hand(term: LearnedTerm | None, base_rotation: F64, tool_points: F64, q: F64,
                 y: F64, rn: F64, tool: F64) -> tuple[F64, F64]:
    """The tool point y (T, 3) and hand rotation rn (T, 3, 3) of the physical model at
    commands q (base frame), moved by the term's rigid hand correction (:func:`hand_correction`;
    ``tool_points``: the term's points from the end point in the hand frame, (M, 3); ``tool``:
    y's point, (3,)); unchanged without a term."""
    if term is None:
        return y, rn
    d, rw = hand_correction(term, q, np.einsum("tij,mj->tmi", rn, tool_points), base_rotation)
    arm = rn @ tool
    return y + d + np.einsum("tij,tj->ti", rw, arm) - arm, rw @ rn
