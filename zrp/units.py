"""Units: the one home of every length unit the model format accepts, and of standard gravity.

Every layer converts through :func:`metres_per_unit`; an unknown unit is an error everywhere
(:class:`zrp.Manipulator` checks its ``length_unit`` at construction).
"""

from __future__ import annotations

from zrp.errors import UnitError

__all__ = ["G_STANDARD", "LENGTH_UNITS", "canonical_length_unit", "metres_per_unit"]

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
