"""Units: the one home of every length unit the model format accepts, and of standard gravity.

Every layer converts through :func:`metres_per_unit`; an unknown unit is an error everywhere
(:class:`zrp.Manipulator` checks its ``length_unit`` at construction).

**The one rule for angles and lengths** (every command, every CSV; :func:`joint_values_to_rad`
applies it to joint values):

* a CSV column may declare its unit in brackets: ``q1[deg]``, ``q1[rad]``, ``x[mm]``, ``x[m]``
  (:func:`split_unit`); a declared unit always holds;
* a joint column without a unit is in radians (revolute) or the model's length unit
  (prismatic); a length column without a unit is in the model's length unit;
* on the command line, ``--deg`` means degrees for every angle of that command: the values
  typed (``--q``, ``--q0``, ``--limits``), the joint columns without a unit of the files read,
  and the files written (which then declare ``q1[deg]``). Without it: radians. A declared
  ``[rad]`` column read with ``--deg`` is an error (the two disagree);
* a value that cannot be an angle in its unit is a named :class:`~zrp.errors.UnitError`
  (:func:`joint_values_to_rad` states exactly what can and cannot be told).

**Time-series quantities** (the joint torque log, :mod:`zrp.gap.dynamics.data`): a column
holds one kind of :data:`QUANTITY_UNITS` (time, position, velocity, effort, current, mass),
declared the same way (``tau3[mNm]``, or with a space, ``tau3 [mNm]``); :func:`si_factor`
gives the factor of its unit to the SI unit of its kind (:data:`SI_UNITS`).
"""

from __future__ import annotations

import math
import re

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.errors import UnitError

__all__ = [
    "ANGLE_UNITS",
    "G_STANDARD",
    "LENGTH_UNITS",
    "QUANTITY_UNITS",
    "RADIAN_LOOK_MIN",
    "RADIAN_LOOK_ROWS",
    "SI_UNITS",
    "TRACKER_NOISE_MM",
    "angle_bounds",
    "canonical_angle_unit",
    "canonical_length_unit",
    "joint_column_units",
    "joint_values_to_rad",
    "length_scale",
    "metres_per_unit",
    "si_factor",
    "split_unit",
    "units_per_mm",
]

#: Radians per angle unit.
ANGLE_UNITS: dict[str, float] = {"rad": 1.0, "deg": math.pi / 180.0}
_ANGLE_ALIASES = {"radian": "rad", "radians": "rad", "degree": "deg", "degrees": "deg",
                  "°": "deg"}
_UNIT_RE = re.compile(r"^\s*([^\[\]]*?)\s*\[\s*([^\[\]]*?)\s*\]\s*$")

#: Standard gravity, m/s^2 (CGPM 1901).
G_STANDARD = 9.80665

#: Metres per model length unit.
LENGTH_UNITS: dict[str, float] = {
    "m": 1.0,
    "dm": 0.1,
    "cm": 0.01,
    "mm": 1e-3,
    "um": 1e-6,
    "in": 0.0254,
    "ft": 0.3048,
}
_ALIASES = {"meter": "m", "metre": "m", "meters": "m", "metres": "m", "millimeter": "mm",
            "millimetre": "mm", "millimeters": "mm", "millimetres": "mm", "µm": "um",
            "micron": "um", "inch": "in", "inches": "in", "centimeter": "cm",
            "centimetre": "cm", "foot": "ft", "feet": "ft"}


def canonical_length_unit(unit: str, field: str = "length_unit") -> str:
    """The canonical name (a key of :data:`LENGTH_UNITS`) of ``unit`` or one of its aliases.

    Raises:
        InputError: naming ``field`` and listing the known units.
    """
    if not isinstance(unit, str):
        raise UnitError(f"{field}: expected a unit name such as 'mm', got {unit!r}")
    key = unit.strip().lower()
    key = _ALIASES.get(key, key)
    if key not in LENGTH_UNITS:
        raise UnitError(f"{field}: unknown length unit {unit!r}; expected one of "
                         f"{sorted(LENGTH_UNITS)}")
    return key


def metres_per_unit(unit: str, field: str = "length_unit") -> float:
    """Scale from a model length unit (``"mm"``, ``"m"``, ``"in"``...) to metres.

    Raises:
        InputError: naming ``field`` and listing the known units.
    """
    return LENGTH_UNITS[canonical_length_unit(unit, field)]


#: A laser tracker's typical noise per coordinate, mm (the default of the commands that
#: simulate or plan measurements; convert with :func:`units_per_mm`).
TRACKER_NOISE_MM = 0.02


def units_per_mm(unit: str, field: str = "length_unit") -> float:
    """How many ``unit`` make one millimetre (1 for ``"mm"``, 1e-3 for ``"m"``): a length
    fixed in mm, such as an instrument's noise, in a model's own unit."""
    return 1e-3 / metres_per_unit(unit, field)



def canonical_angle_unit(unit: str, field: str = "angle unit") -> str:
    """``"rad"`` or ``"deg"`` for ``unit`` or one of its aliases (degrees, radian, °...).

    Raises:
        UnitError: naming ``field`` and listing the known angle units.
    """
    key = unit.strip().lower() if isinstance(unit, str) else None
    key = _ANGLE_ALIASES.get(key, key) if key is not None else None
    if key not in ANGLE_UNITS:
        raise UnitError(f"{field}: unknown angle unit {unit!r}; expected one of "
                        f"{sorted(ANGLE_UNITS)}")
    return str(key)


def split_unit(column: str, field: str = "column") -> tuple[str, str | None]:
    """A CSV column name and its declared unit: ``"q1[deg]"`` -> ``("q1", "deg")``,
    ``"x"`` -> ``("x", None)`` (the unit is returned as written; check it with
    :func:`canonical_angle_unit` or :func:`canonical_length_unit`).

    Raises:
        UnitError: a bracket that does not close, or an empty unit (naming ``field``).
    """
    if "[" not in column and "]" not in column:
        return column.strip(), None
    m = _UNIT_RE.match(column)
    if m is None or not m.group(2) or not m.group(1):
        raise UnitError(f"{field}: {column!r} is not NAME or NAME[UNIT] (e.g. q1[deg], "
                        "x[mm])")
    return m.group(1), m.group(2)


#: Per kind of time-series quantity, unit name (lower case) -> factor to SI (value * factor).
#: Joint values are rad (hinges) or m (slides); efforts N m (hinges) or N (slides).
QUANTITY_UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "position": {**ANGLE_UNITS, **LENGTH_UNITS},
    "velocity": {"rad/s": 1.0, "deg/s": math.pi / 180.0, "m/s": 1.0, "mm/s": 1e-3},
    "effort": {"nm": 1.0, "n m": 1.0, "n.m": 1.0, "mnm": 1e-3, "n": 1.0},
    "current": {"a": 1.0, "ma": 1e-3},
    "mass": {"kg": 1.0, "g": 1e-3},
}

#: The unit of each kind a column without a declared unit is in (hinge joints; slides: m,
#: m/s, N).
SI_UNITS = {"time": "s", "position": "rad", "velocity": "rad/s", "effort": "Nm",
            "current": "A", "mass": "kg"}


def si_factor(kind: str, unit: str | None, field: str = "column") -> float:
    """The factor to SI (:data:`SI_UNITS`) of ``unit``, a unit of ``kind`` (a key of
    :data:`QUANTITY_UNITS`); None (no unit declared): 1.

    Raises:
        UnitError: an unknown unit, naming ``field`` and listing the units of ``kind``.
    """
    if unit is None:
        return 1.0
    table = QUANTITY_UNITS[kind]
    key = unit.strip().lower()
    if key not in table:
        si = SI_UNITS[kind]
        shown = ", ".join([si, *sorted(k for k in table if k != si.lower())])
        raise UnitError(f"{field} has unit [{unit}]; a {kind} column takes one of {shown}")
    return table[key]


def length_scale(unit: str | None, model_unit: str, field: str = "column") -> float:
    """Factor from a declared length ``unit`` (None: the model's) to the model's unit."""
    if unit is None:
        return 1.0
    return metres_per_unit(unit, field) / metres_per_unit(model_unit, "model.length_unit")


#: A degree table whose revolute values all lie within +-2 pi is read as radians in a degree
#: column when its largest |value| is at least this (0.5: half a radian, 29 degrees, is an
#: ordinary move; a degree program moving every joint by less than 6.3 degrees is not)...
RADIAN_LOOK_MIN = 0.5
#: ... and it has at least this many rows (one typed vector cannot tell: 5 deg is an angle).
RADIAN_LOOK_ROWS = 3
_TURN = 2.0 * math.pi
_FLAG = "deg=True (--deg on the command line)"


def _where(src: str, lines: ArrayLike | None, i: int) -> str:
    if lines is None:
        return src if i < 0 else f"{src} row {i + 1}"
    return f"{src} line {int(np.asarray(lines)[i])}"


def _fix(col: str, unit: str, flag: str, header: bool) -> str:
    switch = f"with {flag}" if unit == "deg" else f"without {flag}"
    return (f"declare the column {col}[{unit}] (or read the file {switch})" if header
            else f"give them {switch} if they are in {'degrees' if unit == 'deg' else 'radians'}")


def _angle_units(units: list[str | None] | str | None, cols: list[str], src: str
                 ) -> list[str]:
    unit = [units] * len(cols) if isinstance(units, str) or units is None else list(units)
    return [canonical_angle_unit(u, f"{src} column {c}") if u is not None else "rad"
            for u, c in zip(unit, cols, strict=True)]


def _check_degree_columns(a: NDArray[np.float64], cols: list[str], src: str, flag: str,
                          header: bool) -> None:
    """Radians in degree columns (|values| ``a``, rows x columns): see joint_values_to_rad."""
    if a.max() <= _TURN and a.max() >= RADIAN_LOOK_MIN:
        raise UnitError(f"{src}: columns {', '.join(cols)} are in degrees, but every value lies "
                        f"within +-2 pi (largest {a.max():.4g}) over {len(a)} rows: these look "
                        f"like radians in a degree column; {_fix(cols[0], 'rad', flag, header)}"
                        " (a degree program moving every joint by less than 6.3 degrees: write "
                        "it in rad)")


def joint_values_to_rad(values: ArrayLike, revolute: ArrayLike, units: list[str | None] | str,
                        *, src: str, names: list[str] | None = None,
                        lines: ArrayLike | None = None, bounds: ArrayLike | None = None,
                        flag: str = _FLAG, header: bool = True) -> NDArray[np.float64]:
    """Joint values (R, n) in their declared units, checked, to rad (revolute columns;
    prismatic columns are returned as they are, in the model's length unit).

    Args:
        values: the joint values as read, shape (R, n) (or (n,): one typed vector).
        revolute: which columns are revolute joints, (n,) bool.
        units: per column ``"rad"``/``"deg"`` (or None: rad), or one unit for all.
        src: what to name in an error (file, option); ``names``: column names (q1..qn);
            ``lines``: the file line of each row; ``flag``: the switch to degrees the user
            has (``"--deg"`` on the command line); ``header``: the values have a header
            whose columns can declare a unit (a file; not typed values).
        bounds: per revolute column, the largest |angle| in rad the joint can take (default
            2 pi; a joint whose limits reach beyond one turn passes them).

    The checks (each a :class:`~zrp.errors.UnitError` naming the column, line and value):

    * **degrees in a radian column**: a value with |q| above its bound (2 pi or the joint's
      wider limit) cannot be an angle in rad. Degrees that all stay within +-2 pi (a program
      moving every joint by less than 6.3 degrees) cannot be told from radians: not checked;
    * **radians in a degree column**: a table of at least :data:`RADIAN_LOOK_ROWS` rows whose
      degree values all lie within +-2 pi while the largest is at least
      :data:`RADIAN_LOOK_MIN` (a span of radians: every joint within 6.3 degrees is not a
      robot program; half a radian is an ordinary move). A degree program that truly moves
      that little is refused too: write it in rad. Fewer rows, or values all below
      :data:`RADIAN_LOOK_MIN`, cannot be told: not checked.
    """
    q = np.array(values, dtype=float)
    one = q.ndim == 1
    q = np.atleast_2d(q)
    n = q.shape[1]
    rev = np.asarray(revolute, dtype=bool)
    cols = names or [f"q{k}" for k in range(1, n + 1)]
    deg = rev & (np.array(_angle_units(units, cols, src)) == "deg")
    bnd = np.full(n, _TURN) if bounds is None else np.maximum(np.asarray(bounds, float), _TURN)
    big = (rev & ~deg)[None, :] & (np.abs(q) > bnd[None, :] + 1e-9)
    if big.any():
        i, k = (int(v) for v in np.argwhere(big)[0])
        raise UnitError(f"{_where(src, lines, -1 if one else i)}: {'column ' if header else ''}"
                        f"{cols[k]} is {q[i, k]:g}, "
                        f"beyond {bnd[k]:.4g} rad (one turn, or the joint's limit): it cannot "
                        f"be an angle in rad and looks like degrees; "
                        f"{_fix(cols[k], 'deg', flag, header)}")
    if deg.any() and len(q) >= RADIAN_LOOK_ROWS:
        _check_degree_columns(np.abs(q[:, deg]), [c for c, d in zip(cols, deg, strict=True) if d],
                              src, flag, header)
    q[:, deg] = np.radians(q[:, deg])
    return q[0] if one else q


def joint_column_units(declared: list[str | None], revolute: ArrayLike, deg: bool, *,
                       src: str, length_unit: str, names: list[str] | None = None,
                       flag: str = _FLAG) -> tuple[list[str], NDArray[np.float64]]:
    """The unit of each joint column by the rule of this module: a declared unit holds; a
    revolute column without one is in degrees with ``deg``, else rad; a prismatic column
    without one is in the model's ``length_unit``.

    Returns:
        the angle unit per column (``"rad"``/``"deg"``; ``"rad"`` for prismatic columns) and
        the factor of each prismatic column to the model's length unit (1 for revolute ones).

    Raises:
        UnitError: an angle unit on a prismatic joint, a length unit on a revolute one, an
            unknown unit, or a declared ``[rad]`` read with ``deg`` (they disagree).
    """
    rev = np.asarray(revolute, dtype=bool)
    cols = names or [f"q{k}" for k in range(1, len(rev) + 1)]
    angle, scale = [], np.ones(len(rev))
    for k, (u, c) in enumerate(zip(declared, cols, strict=True)):
        field = f"{src} column {c}[{u}]"
        if not rev[k]:
            if u is not None and u.strip().lower() in {*ANGLE_UNITS, *_ANGLE_ALIASES}:
                raise UnitError(f"{field}: joint {c} is prismatic; expected a length unit "
                                f"(or none: {length_unit})")
            scale[k] = length_scale(u, length_unit, field)
            angle.append("rad")
        elif u is None:
            angle.append("deg" if deg else "rad")
        else:
            if u.strip().lower() in LENGTH_UNITS or u.strip().lower() in _ALIASES:
                raise UnitError(f"{field}: joint {c} is revolute; expected rad or deg")
            unit = canonical_angle_unit(u, field)
            if deg and unit == "rad":
                raise UnitError(f"{field}: the column declares rad but {flag} says degrees; "
                                f"drop {flag} or the declared unit")
            angle.append(unit)
    return angle, scale


def angle_bounds(lower: ArrayLike, upper: ArrayLike) -> NDArray[np.float64]:
    """Per joint, the largest |angle| (rad) its limits allow (0 without limits: then one turn
    bounds it in :func:`joint_values_to_rad`)."""
    lim = np.maximum(np.abs(np.asarray(lower, dtype=float)), np.abs(np.asarray(upper, dtype=float)))
    return np.where(np.isfinite(lim), lim, 0.0)
