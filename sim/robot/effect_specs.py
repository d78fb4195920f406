"""Hidden effects written as short text specs: ``NAME[:JOINT][:hH]=VALUE[UNIT]``.

``backlash:1=0.8mrad``, ``thermal_expansion=12ppm/K``, ``link_length:4=0.1,0.2,-0.1mm``... one
spec per effect and joint; :func:`parse_effects` turns a list of them into
:class:`sim.robot.effects.HiddenEffects` checked against a model. Error messages name the spec and
``field`` (the argument, or the command-line option that carried it).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

from sim.robot.effects import EFFECT_NAMES, HiddenEffects
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = ["SPEC_FORMS", "parse_effects"]

_ANGLE = {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "deg": math.pi / 180.0}
_SCALE = {"": 1.0, "ppm": 1e-6}
_COMPLIANCE = {"rad/Nm": 1.0, "mrad/Nm": 1e-3, "urad/Nm": 1e-6}
_THERMAL = {"/K": 1.0, "1/K": 1.0, "ppm/K": 1e-6}

#: Per effect: (unit factors, or None for a length in any unit of :data:`zrp.units`;
#: number of values; the unit when none is written).
SPEC_FORMS: Mapping[str, tuple[Mapping[str, float] | None, int, str]] = {
    "joint_offset": (_ANGLE, 1, "rad"),
    "encoder_scale": (_SCALE, 1, ""),
    "cyclic_error": (_ANGLE, 1, "rad"),
    "link_length": (None, 3, ""),
    "axis_misalignment": (_ANGLE, 2, "rad"),
    "joint_compliance": (_COMPLIANCE, 1, "rad/Nm"),
    "backlash": (_ANGLE, 1, "rad"),
    "thermal_expansion": (_THERMAL, 1, "/K"),
}
_GLOBAL = ("thermal_expansion",)  # effects without a joint
_SPEC = re.compile(r"^\s*([a-z_]+)(?::(\d+))?(?::h(\d+))?\s*=\s*([-+0-9.eE,\s]+?)\s*"
                   r"((?:[A-Za-df-z/][A-Za-z/0-9]*)?)\s*$")


def _factor(table: Mapping[str, float] | None, unit: str, model: Manipulator,
            where: str) -> float:
    """Factor from ``unit`` to the effect's own unit (the model's for lengths)."""
    if table is None:
        return (metres_per_unit(unit, f"{where} unit") / metres_per_unit(model.length_unit)
                if unit else 1.0)
    if unit not in table:
        raise InputError(f"{where}: unit {unit!r}; expected one of "
                         f"{', '.join(u or '(none)' for u in table)}")
    return table[unit]


def _match(spec: str, where: str) -> tuple[str, str | None, str | None, str, str]:
    """(name, joint, harmonic, value list, unit) as written in ``spec``; the name known."""
    m = _SPEC.match(spec)
    if not m:
        raise InputError(f"{where}: expected NAME[:JOINT]=VALUE[UNIT], e.g. "
                         "backlash:1=0.8mrad or thermal_expansion=12ppm/K")
    name, joint, harm, value, unit = m.groups()
    if name not in EFFECT_NAMES:
        raise InputError(f"{where}: unknown effect {name!r}; expected one of "
                         f"{', '.join(EFFECT_NAMES)}")
    return name, joint, harm, value, unit


def _numbers(value: str, where: str) -> list[float]:
    """The comma-separated numbers of a spec's value."""
    try:
        return [float(v) for v in value.replace(" ", "").split(",") if v]
    except ValueError:
        raise InputError(f"{where}: {value!r} is not a number list") from None


def _check_place(name: str, joint: str | None, harm: str | None, where: str) -> None:
    """A joint for per-joint effects only, a harmonic for ``cyclic_error`` only."""
    if name in _GLOBAL and joint is not None:
        raise InputError(f"{where}: {name} takes no joint")
    if name not in _GLOBAL and joint is None:
        raise InputError(f"{where}: {name} needs a joint, e.g. {name}:2=...")
    if harm is not None and name != "cyclic_error":
        raise InputError(f"{where}: :hH (harmonic) is for cyclic_error only")


def _entry(name: str, values: list[float], harm: str | None) -> Any:
    """What :class:`HiddenEffects` holds for one spec: a tuple of several values, the
    (harmonic, amplitude, phase) of a ``cyclic_error``, or the value."""
    if len(values) > 1:
        return tuple(values)
    if name == "cyclic_error":
        return (int(harm or 1), values[0], 0.0)
    return values[0]


def _parse_one(spec: str, model: Manipulator, field: str) -> tuple[str, int | None, Any]:
    """(effect, joint or None, value in the effect's unit) of one spec."""
    where = f"{field} {spec!r}"
    name, joint, harm, value, unit = _match(spec, where)
    vals = _numbers(value, where)
    _check_place(name, joint, harm, where)
    table, count, default_unit = SPEC_FORMS.get(name, (_ANGLE, 1, "rad"))
    if len(vals) != count:
        raise InputError(f"{where}: {name} takes {count} value(s), got {len(vals)}")
    factor = _factor(table, unit or default_unit, model, where)
    entry = _entry(name, [x * factor for x in vals], harm)
    return name, None if joint is None else int(joint), entry


def parse_effects(specs: Sequence[str], model: Manipulator, payload: float = 0.0, *,
                  field: str = "specs") -> HiddenEffects:
    """Hidden effects from specs ``NAME[:JOINT][:hH]=VALUE[UNIT]``.

    Units (default first): ``joint_offset``, ``backlash``, ``cyclic_error`` (amplitude of
    sin(h q), h from ``:hH``, default 1) in rad, mrad, urad or deg; ``encoder_scale``
    dimensionless or ppm; ``link_length:K=DX,DY,DZ`` in the model's length unit (or mm, m,
    um...); ``axis_misalignment:K=A,B`` (tilts towards t1, t2) in rad, mrad, urad, deg;
    ``joint_compliance`` in rad/Nm, mrad/Nm, urad/Nm; ``thermal_expansion`` (no joint) in /K
    or ppm/K. Example: ``backlash:1=0.8mrad``, ``thermal_expansion=12ppm/K``.

    Args:
        specs: the specs, one effect (and joint) each.
        model: the nominal model (joint range, length unit).
        payload: kg at the end-effector point.
        field: how messages name ``specs`` (the command line passes its option).
    """
    kw: dict[str, Any] = {}
    for spec in specs:
        name, joint, entry = _parse_one(spec, model, field)
        if joint is None:
            kw[name] = entry
        else:
            kw.setdefault(name, {})[joint] = entry
    eff = HiddenEffects(payload=payload, **kw)
    eff.check(model)
    return eff
