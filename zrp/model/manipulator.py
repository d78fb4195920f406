"""The manipulator model of the zero-reference-position (ZRP) method.

All vectors are expressed in the base frame with every joint at zero (the zero reference
position, q = 0). Per joint ``k`` (1-based in messages, as in the paper):

* ``axis`` is u_{k,0}, the unit vector along the joint's axis of motion;
* ``body`` is b_{k,0}, from a point on joint k-1 (the base origin for k = 1) to a point on
  joint k.

The end effector carries b_{n+1,0} (from the point on joint n to the end-effector point p),
the axial unit vector u_{a,0} (along the gripper) and the transverse unit vector u_{t,0},
perpendicular to it.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import ModelError, ZRPWarning
from zrp.limits import MAX_LENGTH
from zrp.units import canonical_length_unit, units_per_mm

__all__ = [
    "JOINT_TYPES",
    "EndEffector",
    "Joint",
    "Manipulator",
    "check_limits",
    "check_unit_vector",
    "check_vector3",
    "derived",
    "hand_frame",
]

T = TypeVar("T")
JOINT_TYPES = ("revolute", "prismatic")
JointType = Literal["revolute", "prismatic"]

#: Axes whose norm differs from 1 by at most this much are normalised silently.
UNIT_EXACT_TOL = 1e-12
#: Axes whose norm differs from 1 by at most this much are normalised with a warning;
#: beyond it the input is taken to be a mistake and rejected.
UNIT_WARN_TOL = 1e-3
#: Largest |u_a . u_t| accepted as perpendicular.
PERP_TOL = 1e-9


def check_vector3(value: ArrayLike, where: str) -> F64:
    """Coerce ``value`` to a finite float vector of shape (3,), or raise naming ``where``.

    Only real numbers are accepted (not strings, booleans or complex numbers), each of
    magnitude at most :data:`MAX_LENGTH`.
    """
    raw = np.asarray(value, dtype=object) if not isinstance(value, np.ndarray) else value
    if raw.dtype.kind not in "iuf" and not (
            raw.dtype == object and all(_is_real(v) for v in np.ravel(raw))):
        raise ModelError(f"{where}: expected 3 numbers, got {_short(value)}")
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"{where}: expected 3 numbers, got {_short(value)}") from exc
    if arr.shape != (3,):
        raise ModelError(f"{where}: expected 3 numbers (shape (3,)), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{where}: expected finite numbers, got {arr.tolist()}")
    if np.max(np.abs(arr)) > MAX_LENGTH:
        raise ModelError(f"{where}: component {np.max(np.abs(arr)):g} is out of range; expected "
                         f"magnitudes up to {MAX_LENGTH:g} (in the model's length unit)")
    return arr


def _is_real(v: object) -> bool:
    """A real number: int or float (NumPy's included), not a bool, string or complex."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(
        v, (bool, np.bool_))


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def check_unit_vector(value: ArrayLike, where: str) -> F64:
    """Coerce to a unit 3-vector: exact, normalised with a warning when off by a little, or an
    error when zero or far from unit length."""
    arr = check_vector3(value, where)
    norm = float(np.linalg.norm(arr))
    if norm < 1e-9:
        raise ModelError(f"{where}: is a zero vector; expected a unit vector such as [0, 0, 1]")
    dev = abs(norm - 1.0)
    if dev > UNIT_WARN_TOL:
        raise ModelError(
            f"{where}: has norm {norm:.6g}; expected a unit vector (norm 1 within "
            f"{UNIT_WARN_TOL:g}), e.g. {np.round(arr / norm, 6).tolist()}"
        )
    if dev > UNIT_EXACT_TOL:
        warnings.warn(
            f"{where}: norm {norm:.12g} is not 1; normalised", ZRPWarning, stacklevel=4
        )
    return arr / norm


def check_limits(value: object, where: str) -> tuple[float, float] | None:
    """``None`` or a pair (lo, hi) of numbers with lo <= hi (either may be -inf/+inf)."""
    if value is None:
        return None
    try:
        lo, hi = (float(x) for x in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError) as exc:
        raise ModelError(f"{where}: expected [lo, hi] (two numbers), got {value!r}") from exc
    if np.isnan(lo) or np.isnan(hi) or not lo <= hi:
        raise ModelError(f"{where}: expected lo <= hi, got [{lo!r}, {hi!r}]")
    return (lo, hi)


def _frozen(arr: F64) -> F64:
    arr = np.array(arr, dtype=float)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Joint:
    """One joint: its type, axis u_{k,0} and body vector b_{k,0} (length unit of the model).

    ``index`` (1-based) and ``name`` only serve error messages and output labels.
    ``limits`` = (lo, hi) bounds q_k (rad, or the length unit for a prismatic joint; None:
    unlimited, e.g. a URDF continuous joint); ``velocity_limit`` bounds |qdot_k| (rad/s or
    length unit/s; None: not given).
    """

    type: JointType
    axis: F64
    body: F64
    name: str = ""
    index: int = field(default=0, compare=False)
    limits: tuple[float, float] | None = None
    velocity_limit: float | None = None

    def __post_init__(self) -> None:
        label = f"joint {self.index}" if self.index else "joint"
        if self.name:
            label += f" ({self.name})"
        if self.type not in JOINT_TYPES:
            raise ModelError(
                f"{label} type: {self.type!r} is not a joint type; expected one of {JOINT_TYPES}"
            )
        object.__setattr__(self, "axis", _frozen(check_unit_vector(self.axis, f"{label} axis")))
        object.__setattr__(self, "body", _frozen(check_vector3(self.body, f"{label} body")))
        object.__setattr__(self, "limits", check_limits(self.limits, f"{label} limits"))
        if self.velocity_limit is not None:
            v = self.velocity_limit
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                    or not np.isfinite(v) or v <= 0:
                raise ModelError(f"{label} velocity_limit: expected a finite number > 0, got "
                                 f"{v!r}")
            object.__setattr__(self, "velocity_limit", float(v))

    @property
    def is_prismatic(self) -> bool:
        return self.type == "prismatic"


@dataclass(frozen=True, eq=False)
class EndEffector:
    """End effector: b_{n+1,0}, the axial u_{a,0} and transverse u_{t,0} unit vectors."""

    body: F64
    axial: F64
    transverse: F64

    def __post_init__(self) -> None:
        body = check_vector3(self.body, "end_effector body")
        ua = check_unit_vector(self.axial, "end_effector axial")
        ut = check_unit_vector(self.transverse, "end_effector transverse")
        dot = float(ua @ ut)
        if abs(dot) > PERP_TOL:
            raise ModelError(
                f"end_effector axial and transverse: must be perpendicular, but their dot product"
                f" is {dot:.3g} (angle {np.degrees(np.arccos(np.clip(dot, -1, 1))):.6g} deg)"
            )
        object.__setattr__(self, "body", _frozen(body))
        object.__setattr__(self, "axial", _frozen(ua))
        object.__setattr__(self, "transverse", _frozen(ut))

    @property
    def frame(self) -> F64:
        """Hand frame at q = 0, columns (u_t x u_a, u_t, u_a) (normal, sliding, approach)."""
        return hand_frame(self.axial, self.transverse)


def hand_frame(axial: ArrayLike, transverse: ArrayLike) -> F64:
    """Right-handed frame with columns (u_t x u_a, u_t, u_a): shapes (..., 3) -> (..., 3, 3).

    The approach (z) column is the axial vector and the sliding (y) column the transverse one,
    as in the usual (n, s, a) gripper convention.
    """
    ua = np.asarray(axial, dtype=float)
    ut = np.asarray(transverse, dtype=float)
    return np.stack([np.cross(ut, ua), ut, ua], axis=-1)


@dataclass(frozen=True, eq=False)
class Manipulator:
    """An immutable serial manipulator in zero-reference-position form.

    Attributes:
        joints: base to tip.
        end_effector: the tool point and its orientation vectors.
        name: free text.
        length_unit: unit of every body vector and prismatic joint value, e.g. "mm"; one of
            :data:`zrp.units.LENGTH_UNITS` or an alias ("millimetre", "inch"...), kept as
            given. An unknown unit is a :class:`~zrp.errors.UnitError` (a ModelError and an
            InputError).
    """

    joints: tuple[Joint, ...]
    end_effector: EndEffector
    name: str = "manipulator"
    length_unit: str = "mm"

    def __post_init__(self) -> None:
        joints = tuple(self.joints)
        if not joints:
            raise ModelError("joints: a manipulator needs at least one joint; got none")
        for k, j in enumerate(joints, start=1):
            if not isinstance(j, Joint):
                raise ModelError(f"joint {k}: expected a zrp.Joint, got {type(j).__name__}")
        if not isinstance(self.end_effector, EndEffector):
            raise ModelError(
                f"end_effector: expected a zrp.EndEffector, got {type(self.end_effector).__name__}"
            )
        # kept as the user spelled it ("mm", "millimetre"...), only checked here; an unknown
        # unit raises UnitError, both a ModelError and an InputError
        canonical_length_unit(self.length_unit, "length_unit")
        # Re-index so that every joint knows its 1-based position (used in messages).
        joints = tuple(
            j if j.index == k else dataclasses.replace(j, index=k)
            for k, j in enumerate(joints, start=1)
        )
        object.__setattr__(self, "joints", joints)

    # ---- constructors ---------------------------------------------------------------------
    @classmethod
    def from_arrays(
        cls,
        axes: ArrayLike,
        bodies: ArrayLike,
        *,
        axial: ArrayLike,
        transverse: ArrayLike,
        types: Sequence[str] | str = "revolute",
        name: str = "manipulator",
        length_unit: str = "mm",
        joint_names: Sequence[str] | None = None,
        limits: Sequence[tuple[float, float] | None] | None = None,
        velocity_limits: Sequence[float | None] | None = None,
    ) -> Manipulator:
        """Build from stacked arrays.

        Args:
            axes: u_{k,0}, shape (n, 3).
            bodies: b_{k,0} for k = 1..n+1, shape (n + 1, 3); the last row is the end effector's.
            axial, transverse: u_{a,0} and u_{t,0}, shape (3,).
            types: one type for all joints, or one per joint.
            limits: per joint (lo, hi) or None, rad or length unit; velocity_limits: per joint
                or None.
        """
        axes = np.asarray(axes, dtype=float)
        bodies = np.asarray(bodies, dtype=float)
        if axes.ndim != 2 or axes.shape[1] != 3:
            raise ModelError(f"axes: expected shape (n, 3), got {axes.shape}")
        n = axes.shape[0]
        if bodies.shape != (n + 1, 3):
            raise ModelError(f"bodies: expected shape ({n + 1}, 3) for {n} joints (the last row is "
                             f"the end effector's body vector), got {bodies.shape}")
        if isinstance(types, str):
            types = [types] * n
        if len(types) != n:
            raise ModelError(f"types: expected {n} joint types, got {len(types)}")
        names = list(joint_names) if joint_names is not None else [""] * n
        if len(names) != n or not all(isinstance(s, str) for s in names):
            raise ModelError(f"joint_names: expected {n} strings (one per joint), got "
                             f"{_short(joint_names)}")
        lims = list(limits) if limits is not None else [None] * n
        vels = list(velocity_limits) if velocity_limits is not None else [None] * n
        for label, seq in (("limits", lims), ("velocity_limits", vels)):
            if len(seq) != n:
                raise ModelError(f"{label}: expected {n} entries (one per joint), got {len(seq)}")
        joints = tuple(
            Joint(type=t, axis=axes[k], body=bodies[k], name=names[k], index=k + 1,  # type: ignore[arg-type]
                  limits=lims[k], velocity_limit=vels[k])
            for k, t in enumerate(types)
        )
        return cls(joints, EndEffector(bodies[n], axial, transverse), name, length_unit)

    # ---- derived arrays (cached; the object is immutable) ---------------------------------
    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.joints)

    @cached_property
    def axes(self) -> F64:
        """u_{k,0}, shape (n, 3)."""
        return _frozen(np.stack([j.axis for j in self.joints]))

    @cached_property
    def bodies(self) -> F64:
        """b_{k,0} for k = 1..n+1, shape (n + 1, 3) (last row: the end effector's)."""
        return _frozen(np.stack([*(j.body for j in self.joints), self.end_effector.body]))

    @cached_property
    def prismatic(self) -> NDArray[np.bool_]:
        """Mask of prismatic joints, shape (n,)."""
        m = np.array([j.is_prismatic for j in self.joints], dtype=bool)
        m.setflags(write=False)
        return m

    @property
    def joint_types(self) -> tuple[str, ...]:
        return tuple(j.type for j in self.joints)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names, ``q1``.. ``qn`` where the model gives none."""
        return tuple(j.name or f"q{k}" for k, j in enumerate(self.joints, start=1))

    @cached_property
    def reach(self) -> float:
        """Sum of the body-vector lengths (a bound on |p - base| for revolute arms), length unit.

        Also used as the characteristic length that makes the Jacobian's rows comparable.
        """
        return float(np.sum(np.linalg.norm(self.bodies, axis=1)))

    @property
    def characteristic_length(self) -> float:
        """Length that scales positions to be comparable with angles: the reach, at least 1 mm
        in the model's unit (was 1 length unit: 1 m for a 0.5 m arm described in metres, which
        loosened every threshold of the gap diagnosis scaled by it 2x)."""
        return max(self.reach, units_per_mm(self.length_unit))

    def with_arrays(self, axes: ArrayLike | None = None, bodies: ArrayLike | None = None,
                    axial: ArrayLike | None = None, transverse: ArrayLike | None = None,
                    name: str | None = None) -> Manipulator:
        """A copy with some arrays replaced (same shapes as :attr:`axes`, :attr:`bodies`)."""
        ee = self.end_effector
        return Manipulator.from_arrays(
            self.axes if axes is None else axes,
            self.bodies if bodies is None else bodies,
            axial=ee.axial if axial is None else axial,
            transverse=ee.transverse if transverse is None else transverse,
            types=self.joint_types,
            name=self.name if name is None else name,
            length_unit=self.length_unit,
            joint_names=[j.name for j in self.joints],
            limits=[j.limits for j in self.joints],
            velocity_limits=[j.velocity_limit for j in self.joints],
        )

    @cached_property
    def lower(self) -> F64:
        """Lower joint limits, shape (n,) (-inf where a joint has none)."""
        return _frozen(np.array([j.limits[0] if j.limits else -np.inf for j in self.joints]))

    @cached_property
    def upper(self) -> F64:
        """Upper joint limits, shape (n,) (+inf where a joint has none)."""
        return _frozen(np.array([j.limits[1] if j.limits else np.inf for j in self.joints]))

    @property
    def has_limits(self) -> bool:
        return any(j.limits is not None for j in self.joints)

    def __repr__(self) -> str:
        kinds = "".join("P" if p else "R" for p in self.prismatic)
        return f"Manipulator({self.name!r}, {self.n} joints {kinds}, unit={self.length_unit!r})"


def derived(model: Manipulator, key: str, build: Callable[[Manipulator], T]) -> T:
    """``build(model)``, computed once and kept on the model under ``key`` (the model is
    immutable): for what the layers above derive from it, e.g. the kinematics kernels' arrays."""
    value = model.__dict__.get(key)
    if value is None:
        value = model.__dict__[key] = build(model)
    return value
