"""Units: the one home of every length unit the model format accepts, and of standard gravity.

Every layer converts through :func:`metres_per_unit`; an unknown unit is an error everywhere
(:class:`zrp.Manipulator` checks its ``length_unit`` at construction).
"""

from __future__ import annotations

from zrp.errors import UnitError

__all__ = ["G_STANDARD", "LENGTH_UNITS", "TRACKER_NOISE_MM", "canonical_length_unit",
           "metres_per_unit", "units_per_mm"]

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

