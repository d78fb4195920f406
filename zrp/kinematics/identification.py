"""The kinematic parameter vector of a model and the analytic sensitivities of the end-effector
pose to it (the primitives of identification: calibration, the gap diagnosis and the tolerance
analysis use them).

The *identification Jacobian* (also the basis of calibration) is the derivative of the
end-effector pose with respect to every geometric parameter of a :class:`~zrp.Manipulator`,
evaluated at joint values ``q``. The parameter vector ``x`` (length ``P``) is, in this order:

1. ``b{k}.x``, ``b{k}.y``, ``b{k}.z`` for k = 1..n+1: the components of the zero-reference body
   vectors b_{k,0} (length unit of the model, e.g. mm); ``b{n+1}`` is the end effector's.
2. ``u{k}.t1``, ``u{k}.t2`` for k = 1..n: small tilts (rad) of the joint axis u_{k,0} towards
   its two tangent directions t1, t2 (see :func:`axis_tangents`). A tilt ``w = a t1 + b t2``
   turns u_{k,0} by the angle |w| towards w; the axis keeps passing through the same point.
3. Optionally (``joint_offsets=True``) ``q{k}.offset`` for k = 1..n: joint zero offsets (rad for
   revolute, length unit for prismatic joints), ``q_actual = q + offset``.

So P = 3 (n + 1) + 2 n (+ n). For the PUMA of Table 1: 21 + 12 = 33 (39 with offsets).

Rows follow :func:`zrp.jacobian`: rows 0-2 are the small rotation (rad, base frame) of the
hand, rows 3-5 the displacement of the end-effector point p (length unit). To first order

    rotvec(E_actual * conj(E_nominal)) ~= J[..., 0:3, :] @ dx,
    p_actual - p_nominal                ~= J[..., 3:6, :] @ dx.

Derivation (R_k = rotation of joints 1..k, p_k = point on joint k, eqs (1)-(6)):

* d p / d b_{k,0} = R_{k-1}; body vectors do not change the orientation (the paper's
  observation that link errors leave the orientation unchanged is exact, not approximate).
* Tilting the revolute axis u_{j,0} by du (du perpendicular to u_{j,0}) changes
  Rot(u_{j,0}, q_j) by the small rotation ``sin(q_j) du + (1 - cos(q_j)) u_{j,0} x du``
  (the left Jacobian of SO(3) at q_j u_{j,0}). In the base frame it is
  ``omega = R_{j-1} (...)``, and every point beyond joint j moves by ``omega x (p - p_j)``.
* Tilting a prismatic axis moves p by ``q_j R_{j-1} du`` and leaves the orientation alone.
* A joint offset is a column of the eq (7) Jacobian.

Note that the parameter set is deliberately complete, hence redundant for identification
(e.g. a body-vector component along the joint axis it ends on can be traded against the next
one); use an SVD / QR of the stacked Jacobian to pick an identifiable subset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import (
    er_conjugate,
    er_from_axis_angle,
    er_identity,
    er_multiply,
    matrix_from_er,
    rotvec_from_er,
)

__all__ = [
    "ParameterSpace",
    "apply_parameters",
    "axis_tangents",
    "parameter_jacobian",
    "parameter_names",
    "parameter_space",
    "perturbed_arrays",
    "pose_error",
    "tilt_axes",
]



def axis_tangents(axes: ArrayLike) -> F64:
    """Two tangent unit vectors per axis: shape (..., 3) -> (..., 2, 3).

    ``t1`` is the normalised projection, perpendicular to u, of the base axis e_x, e_y or e_z
    along which u has its smallest |component| (the first of x, y, z on ties); ``t2 = u x t1``.
    For u = (0, 0, 1): t1 = (1, 0, 0), t2 = (0, 1, 0). For u = (0, 1, 0): t1 = (1, 0, 0),
    t2 = (0, 0, -1).
    """
    u = np.asarray(axes, dtype=float)
    if u.shape[-1:] != (3,):
        raise InputError(f"axes: expected shape (..., 3), got {u.shape}")
    m = np.argmin(np.abs(u), axis=-1)
    e = np.zeros(u.shape)
    np.put_along_axis(e, m[..., None], 1.0, axis=-1)
    t1 = e - np.sum(e * u, axis=-1, keepdims=True) * u
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(u, t1)
    return np.stack([t1, t2], axis=-2)


def parameter_names(model: Manipulator, *, joint_offsets: bool = False) -> tuple[str, ...]:
    """Names of the P parameters in Jacobian-column order (see the module docstring)."""
    n = model.n
    names = [f"b{k}.{c}" for k in range(1, n + 2) for c in "xyz"]
    names += [f"u{k}.{t}" for k in range(1, n + 1) for t in ("t1", "t2")]
    if joint_offsets:
        names += [f"q{k}.offset" for k in range(1, n + 1)]
    return tuple(names)


@dataclass(frozen=True, eq=False)
class ParameterSpace:
    """The parameter vector of a model: names, units and groups.

    Attributes:
        names: P names in column order.
        units: P units: the model's length unit for body components (and prismatic offsets),
            "rad" for axis tilts and revolute offsets.
        kind: P labels "body", "tilt" or "offset".
        index: P 1-based joint/body index k.
        tangents: axis tangent directions t1, t2 at q = 0, shape (n, 2, 3).
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    kind: tuple[str, ...]
    index: tuple[int, ...]
    tangents: F64

    def __post_init__(self) -> None:
        p = len(self.names)
        for field in ("units", "kind", "index"):
            if len(getattr(self, field)) != p:
                raise InputError(f"ParameterSpace.{field}: expected {p} entries, got "
                                 f"{len(getattr(self, field))}")
        if self.tangents.ndim != 3 or self.tangents.shape[1:] != (2, 3):
            raise InputError(f"ParameterSpace.tangents: expected shape (n, 2, 3), got "
                             f"{self.tangents.shape}")

    @property
    def size(self) -> int:
        """P, the number of parameters."""
        return len(self.names)

    def mask(self, kind: str) -> NDArray[np.bool_]:
        """Boolean mask, shape (P,), of the parameters of one kind ("body", "tilt", "offset")."""
        if kind not in ("body", "tilt", "offset"):
            raise InputError(f"kind: expected 'body', 'tilt' or 'offset', got {kind!r}")
        return np.array([k == kind for k in self.kind], dtype=bool)


def parameter_space(model: Manipulator, *, joint_offsets: bool = False) -> ParameterSpace:
    """The :class:`ParameterSpace` of ``model`` (names, units, kinds, tangent directions)."""
    n = model.n
    names = parameter_names(model, joint_offsets=joint_offsets)
    unit = model.length_unit
    units = [unit] * (3 * (n + 1)) + ["rad"] * (2 * n)
    kind = ["body"] * (3 * (n + 1)) + ["tilt"] * (2 * n)
    index = [k for k in range(1, n + 2) for _ in range(3)] + [k for k in range(1, n + 1)
                                                              for _ in range(2)]
    if joint_offsets:
        units += [unit if p else "rad" for p in model.prismatic]
        kind += ["offset"] * n
        index += list(range(1, n + 1))
    return ParameterSpace(names, tuple(units), tuple(kind), tuple(index),
                          axis_tangents(model.axes))


def tilt_axes(axes: ArrayLike, tangents: ArrayLike, tilts_rad: ArrayLike) -> F64:
    """Tilt unit axes exactly: u' = cos|w| u + sin|w| w/|w| with w = a t1 + b t2.

    Args:
        axes: u, shape (..., n, 3).
        tangents: t1, t2 per axis, shape (n, 2, 3).
        tilts_rad: (a, b) per axis in rad, shape (..., n, 2).

    Returns:
        unit axes, shape (..., n, 3).
    """
    u = np.asarray(axes, dtype=float)
    tilts = np.asarray(tilts_rad, dtype=float)
    t = np.asarray(tangents, dtype=float)
    # written out rather than one einsum over the tiny (2, 3) axes: 2x faster on 1e5 robots
    w = tilts[..., 0:1] * t[:, 0] + tilts[..., 1:2] * t[:, 1]
    ang = np.sqrt(np.einsum("...i,...i->...", w, w))[..., None]
    return np.cos(ang) * u + (np.sin(ang) / np.where(ang > 0.0, ang, 1.0)) * w


def _check_dx(space: ParameterSpace, dx: ArrayLike, name: str = "dx") -> F64:
    try:
        arr = np.asarray(dx, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected numbers, got {type(dx).__name__}") from exc
    if arr.ndim == 0 or arr.shape[-1] != space.size:
        raise InputError(f"{name}: expected shape (..., {space.size}) (one value per parameter "
                         f"{space.names[0]}..{space.names[-1]}), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite values")
    return arr


def perturbed_arrays(model: Manipulator, dx: ArrayLike, *,
                     joint_offsets: bool = False) -> tuple[F64, F64, F64]:
    """Exact (nonlinear) perturbation of the model's arrays by parameter steps ``dx``.

    Args:
        dx: parameter steps in parameter units, shape (..., P).

    Returns:
        axes shape (..., n, 3), bodies shape (..., n + 1, 3), joint offsets shape (..., n)
        (zeros when ``joint_offsets`` is False).
    """
    space = parameter_space(model, joint_offsets=joint_offsets)
    dx = _check_dx(space, dx)
    n = model.n
    nb = 3 * (n + 1)
    batch = dx.shape[:-1]
    bodies = model.bodies + dx[..., :nb].reshape(*batch, n + 1, 3)
    axes = tilt_axes(np.broadcast_to(model.axes, (*batch, n, 3)), space.tangents,
                     dx[..., nb:nb + 2 * n].reshape(*batch, n, 2))
    off = dx[..., nb + 2 * n:] if joint_offsets else np.zeros((*batch, n))
    return axes, bodies, off


def apply_parameters(model: Manipulator, dx: ArrayLike, *,
                     joint_offsets: bool = False) -> tuple[Manipulator, F64]:
    """The model with parameter steps ``dx`` (shape (P,)) applied exactly, and the joint
    offsets (shape (n,), zeros unless ``joint_offsets``) to add to q."""
    dx = np.asarray(dx, dtype=float)
    if dx.ndim != 1:
        raise InputError(f"dx: expected shape (P,), got {dx.shape}")
    axes, bodies, off = perturbed_arrays(model, dx, joint_offsets=joint_offsets)
    return model.with_arrays(axes=axes, bodies=bodies), off


def parameter_jacobian(model: Manipulator, q: ArrayLike, *,
                       joint_offsets: bool = False) -> F64:
    """Identification Jacobian of the end-effector pose: q shape (..., n) -> (..., 6, P).

    Rows: [small hand rotation (rad, base frame); displacement of p (length unit)], as in
    :func:`zrp.jacobian`. Columns: :func:`parameter_names` order (body components, axis
    tilts, optional joint offsets). Units of an entry: row unit per parameter unit.
    """
    q = check_q(model, q)
    batch = q.shape[:-1]
    n = model.n
    space = parameter_space(model, joint_offsets=joint_offsets)
    tang = space.tangents  # (n, 2, 3)
    nb = 3 * (n + 1)
    jac = np.zeros((*batch, 6, space.size))
    e = er_identity(batch)
    pos = np.zeros((*batch, 3))
    rots = np.empty((*batch, n + 1, 3, 3))  # R_{k-1} for k = 1..n+1
    points = np.empty((*batch, n, 3))  # p_k, the point on joint k
    for k in range(n + 1):
        r = matrix_from_er(e)
        rots[..., k, :, :] = r
        jac[..., 3:6, 3 * k:3 * k + 3] = r  # d p / d b_{k,0} = R_{k-1}  (eq 2)
        pos = pos + r @ model.bodies[k]
        if k == n:
            break
        points[..., k, :] = pos
        if model.prismatic[k]:
            pos = pos + q[..., k, None] * (r @ model.axes[k])
        else:
            e = er_multiply(e, er_from_axis_angle(model.axes[k], q[..., k]))  # eqs (4)-(6)
    for j in range(n):
        r = rots[..., j, :, :]
        u = model.axes[j]
        for t in range(2):
            col = nb + 2 * j + t
            du = tang[j, t]
            if model.prismatic[j]:
                jac[..., 3:6, col] = q[..., j, None] * (r @ du)
            else:
                local = (np.sin(q[..., j])[..., None] * du
                         + (1.0 - np.cos(q[..., j]))[..., None] * np.cross(u, du))
                omega = np.einsum("...ij,...j->...i", r, local)
                jac[..., 0:3, col] = omega
                jac[..., 3:6, col] = np.cross(omega, pos - points[..., j, :])
        if joint_offsets:
            col = nb + 2 * n + j
            uj = r @ u
            if model.prismatic[j]:
                jac[..., 3:6, col] = uj
            else:
                jac[..., 0:3, col] = uj
                jac[..., 3:6, col] = np.cross(uj, pos - points[..., j, :])
    return jac


def pose_error(nominal: Manipulator, actual: Manipulator, q: ArrayLike, *,
               q_offset: ArrayLike | None = None) -> F64:
    """Pose error of ``actual`` against ``nominal`` at the same joints, in Jacobian row order.

    Returns ``[rotvec(E_a * conj(E_d)) (rad, base frame); p_a - p_d (length unit)]``, shape
    (..., 6) for q of shape (..., n); to first order it equals
    ``parameter_jacobian(nominal, q) @ dx`` (the residual used for identification).
    """
    if actual.n != nominal.n:
        raise InputError(f"actual: has {actual.n} joints, the nominal model {nominal.n}")
    q = check_q(nominal, q)
    qa = q if q_offset is None else q + check_q(nominal, q_offset, "q_offset")
    p_d, e_d = end_effector_pose(nominal, q)
    p_a, e_a = end_effector_pose(actual, qa)
    rv = rotvec_from_er(er_multiply(e_a, er_conjugate(e_d)))
    return np.concatenate([rv, p_a - p_d], axis=-1)
