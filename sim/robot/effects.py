"""The hidden effects of the "real" robot: what they are, how they are checked and stored.

:class:`HiddenEffects` holds the effects the nominal model does not know about, each switched on
with a magnitude (names as in the gap diagnosis, :data:`zrp.gap.EFFECTS`); how each one emerges
in the simulation is described in :mod:`sim.robot.real`:

* ``joint_offset``, ``encoder_scale``, ``cyclic_error`` (encoder/transmission errors): the
  controller's joint value q maps to the true motor angle q + o + s q + a sin(h q) + b cos(h q)
  (:func:`motor_map`);
* ``link_length`` (body offsets) and ``axis_misalignment`` (tilted joint axes): the real
  geometry is a perturbed copy of the model (:func:`true_geometry`);
* ``joint_compliance``, ``backlash``, ``thermal_expansion`` and the ``payload``: physical
  (servo stiffness, free play with friction, thermal growth, a point mass).

Units: joint values rad (model length unit for prismatic joints), lengths in the model's
length unit, compliance rad/(N m), alpha 1/K, masses kg.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import EFFECTS as GAP_EFFECTS
from zrp.kinematics.identification import axis_tangents, tilt_axes
from zrp.model.manipulator import Manipulator

__all__ = [
    "EFFECT_NAMES",
    "HiddenEffects",
    "default_tool_points",
    "motor_map",
    "true_geometry",
]


#: Effects the real robot can hide: exactly the diagnosis's candidates (one list for both).
EFFECT_NAMES: tuple[str, ...] = GAP_EFFECTS


def freeze(a: ArrayLike) -> F64:
    """A read-only float copy of ``a`` (for the arrays the real robot hands out)."""
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


def finite(v: object, where: str, unit: str) -> float:
    """``v`` as a finite float; an :class:`InputError` naming ``where`` and ``unit`` if not."""
    try:
        x = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: expected a number ({unit}), got {v!r}") from exc
    if not math.isfinite(x):
        raise InputError(f"{where}: expected a finite number ({unit}), got {v!r}")
    return x


def _joint_map(value: Mapping[int, Any] | None, name: str, conv: Any) -> Mapping[int, Any]:
    if value is None:
        return MappingProxyType({})
    if not isinstance(value, Mapping):
        raise InputError(f"{name}: expected a mapping from 1-based joint number to a value, got "
                         f"{type(value).__name__}")
    out: dict[int, Any] = {}
    for k, v in value.items():
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or int(k) < 1:
            raise InputError(f"{name}: key {k!r} is not a 1-based joint number")
        out[int(k)] = conv(v, f"{name}[{int(k)}]")
    return MappingProxyType(dict(sorted(out.items())))


def _vec(n: int, unit: str) -> Any:
    def conv(v: object, where: str) -> tuple[float, ...]:
        arr = np.asarray(v, dtype=float).ravel()
        if arr.shape != (n,) or not np.all(np.isfinite(arr)):
            raise InputError(f"{where}: expected {n} finite numbers ({unit}), got {v!r}")
        return tuple(float(x) for x in arr)
    return conv


def _positive(unit: str) -> Any:
    def conv(v: object, where: str) -> float:
        x = finite(v, where, unit)
        if x <= 0:
            raise InputError(f"{where}: expected a value > 0 ({unit}), got {v!r}")
        return x
    return conv


def _cyclic(v: object, where: str) -> tuple[int, float, float]:
    try:
        h, a, b = v  # type: ignore[misc]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: expected (harmonic h >= 1, sin amplitude rad, cos amplitude "
                         f"rad), got {v!r}") from exc
    if isinstance(h, bool) or int(h) != h or int(h) < 1:
        raise InputError(f"{where}: harmonic {h!r} must be an integer >= 1")
    return (int(h), finite(a, where, "rad"), finite(b, where, "rad"))


@dataclass(frozen=True)
class HiddenEffects:
    """Effects of the real robot that the nominal model does not know (all off by default).

    Joint keys are 1-based. Attributes:
        joint_offset: encoder zero error per joint, rad (model length unit if prismatic); the
            true motor angle is q + offset.
        encoder_scale: scale error per joint (dimensionless): true = q (1 + s).
        cyclic_error: per joint (h, a, b): true += a sin(h q) + b cos(h q), a and b in rad.
        link_length: body-vector error db_k (model length unit, zero-reference base frame) per
            body k = 1..n+1 (n+1: the end effector's).
        axis_misalignment: per joint, tilt (a, b) in rad of the axis towards its tangents t1,
            t2 (:func:`zrp.manufacturing.axis_tangents`), applied exactly (rotation by |w|).
        joint_compliance: per joint, rad/(N m): the servo stiffness is 1/c and has no integral
            action, so the joint deflects by -c tau under the static torque tau it carries.
        backlash: per joint, the total free play b between motor and load, rad; the load lags
            by b/2 behind a slow approach (unless gravity holds it on the other flank).
        thermal_expansion: alpha, 1/K: body vectors scale by 1 + alpha (T - t_ref).
        payload: kg, a point mass at the end-effector point (0: none).
    """

    joint_offset: Mapping[int, float] = field(default_factory=dict)
    encoder_scale: Mapping[int, float] = field(default_factory=dict)
    cyclic_error: Mapping[int, tuple[int, float, float]] = field(default_factory=dict)
    link_length: Mapping[int, tuple[float, float, float]] = field(default_factory=dict)
    axis_misalignment: Mapping[int, tuple[float, float]] = field(default_factory=dict)
    joint_compliance: Mapping[int, float] = field(default_factory=dict)
    backlash: Mapping[int, float] = field(default_factory=dict)
    thermal_expansion: float = 0.0
    payload: float = 0.0

    def __post_init__(self) -> None:
        fin = (lambda v, w: finite(v, w, "see HiddenEffects"))  # noqa: E731
        object.__setattr__(self, "joint_offset", _joint_map(self.joint_offset, "joint_offset",
                                                            fin))
        object.__setattr__(self, "encoder_scale", _joint_map(self.encoder_scale,
                                                             "encoder_scale", fin))
        object.__setattr__(self, "cyclic_error", _joint_map(self.cyclic_error, "cyclic_error",
                                                            _cyclic))
        object.__setattr__(self, "link_length", _joint_map(self.link_length, "link_length",
                                                           _vec(3, "length unit")))
        object.__setattr__(self, "axis_misalignment", _joint_map(
            self.axis_misalignment, "axis_misalignment", _vec(2, "rad")))
        object.__setattr__(self, "joint_compliance", _joint_map(
            self.joint_compliance, "joint_compliance", _positive("rad/(N m)")))
        object.__setattr__(self, "backlash", _joint_map(self.backlash, "backlash",
                                                        _positive("rad")))
        a = finite(self.thermal_expansion, "thermal_expansion", "1/K")
        if abs(a) > 1e-3:
            raise InputError(f"thermal_expansion: {a!r} 1/K is implausible; expected a linear "
                             "expansion coefficient such as 1.2e-5 (steel) or 2.3e-5 (aluminium)")
        object.__setattr__(self, "thermal_expansion", a)
        m = finite(self.payload, "payload", "kg")
        if m < 0:
            raise InputError(f"payload: expected a mass >= 0 kg, got {self.payload!r}")
        object.__setattr__(self, "payload", m)
        for k, s in self.encoder_scale.items():
            if abs(s) >= 0.1:
                raise InputError(f"encoder_scale[{k}]: {s!r} is not a small scale error; "
                                 "expected |s| < 0.1")

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        # the mappings are read-only proxies, which do not pickle: go through the plain form
        return (HiddenEffects.from_dict, (self.to_dict(),))

    @property
    def active(self) -> tuple[str, ...]:
        """Names of the effects switched on (in :data:`EFFECT_NAMES` order)."""
        out = []
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            on = bool(v) if isinstance(v, Mapping) else v != 0.0
            if isinstance(v, Mapping) and name in ("joint_offset", "encoder_scale"):
                on = any(x != 0.0 for x in v.values())
            if on:
                out.append(name)
        return tuple(out)

    def joints(self, effect: str) -> tuple[int, ...]:
        """Joints (bodies for ``link_length``) an effect is switched on for; () if global."""
        if effect not in EFFECT_NAMES:
            raise InputError(f"effect: {effect!r} is not one of {EFFECT_NAMES}")
        v = getattr(self, effect)
        return tuple(sorted(v)) if isinstance(v, Mapping) else ()

    def check(self, model: Manipulator) -> None:
        """Raise :class:`InputError` if a joint or body number does not exist in ``model``."""
        n = model.n
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            if not isinstance(v, Mapping):
                continue
            top = n + 1 if name == "link_length" else n
            bad = [k for k in v if k > top]
            if bad:
                what = "bodies 1.." if name == "link_length" else "joints 1.."
                raise InputError(f"{name}: {bad} out of range; the model {model.name!r} has "
                                 f"{what}{top}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (keys as strings); inverse of :meth:`from_dict`."""
        out: dict[str, Any] = {}
        for name in EFFECT_NAMES:
            v = getattr(self, name)
            out[name] = ({str(k): (list(x) if isinstance(x, tuple) else x) for k, x in v.items()}
                         if isinstance(v, Mapping) else v)
        out["payload"] = self.payload
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HiddenEffects:
        """Build from :meth:`to_dict` output."""
        unknown = set(data) - {*EFFECT_NAMES, "payload"}
        if unknown:
            raise InputError(f"hidden effects: unknown key(s) {sorted(unknown)}; expected "
                             f"{[*EFFECT_NAMES, 'payload']}")
        kw: dict[str, Any] = {}
        for name, v in data.items():
            if isinstance(v, Mapping):
                kw[name] = {int(k): (tuple(x) if isinstance(x, list) else x)
                            for k, x in v.items()}
            else:
                kw[name] = v
        return cls(**kw)


def motor_map(effects: HiddenEffects, q: ArrayLike) -> F64:
    """True motor angles for controller joint values ``q`` (rad), shape (..., n) -> same:
    q + offset + s q + a sin(h q) + b cos(h q) (the encoder/transmission effects)."""
    q = np.asarray(q, dtype=float)
    out = q.copy()
    for k, v in effects.joint_offset.items():
        out[..., k - 1] += v
    for k, s in effects.encoder_scale.items():
        out[..., k - 1] += s * q[..., k - 1]
    for k, (h, a, b) in effects.cyclic_error.items():
        out[..., k - 1] += a * np.sin(h * q[..., k - 1]) + b * np.cos(h * q[..., k - 1])
    return out


def true_geometry(model: Manipulator, effects: HiddenEffects) -> Manipulator:
    """The real robot's geometry at t_ref: body vectors + link_length errors, axes tilted
    exactly by axis_misalignment (:func:`zrp.kinematics.identification.tilt_axes`)."""
    bodies = np.array(model.bodies, dtype=float)
    for k, db in effects.link_length.items():
        bodies[k - 1] += np.asarray(db)
    tilts = np.zeros((model.n, 2))
    for k, ab in effects.axis_misalignment.items():
        tilts[k - 1] = ab
    axes = tilt_axes(model.axes, axis_tangents(model.axes), tilts)
    return model.with_arrays(axes=axes, bodies=bodies, name=f"{model.name} (real)")


def default_tool_points(model: Manipulator) -> F64:
    """Three reflector positions on the tool relative to the end-effector point, in the
    zero-reference base frame, model length unit, shape (3, 3): a triangle of about 6 % of
    the reach (50-70 mm on the PUMA)."""
    base = np.array([[50.0, 0.0, 30.0], [-40.0, 60.0, 30.0], [0.0, -70.0, 40.0]])
    return freeze(base * model.reach / 1244.6)
