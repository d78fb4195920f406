"""One candidate effect of the dynamic gap: a block of regressor columns, linear in its
parameters, with their bounds (the effects themselves: :mod:`zrp.gap.dynamics.effects` and
:mod:`zrp.gap.dynamics.bodies`)."""

from __future__ import annotations

from dataclasses import dataclass

from zrp.arrays import F64

__all__ = ["Effect"]


@dataclass(frozen=True, eq=False)  # identity: its arrays have no one truth value
class Effect:
    """One candidate effect: its regressor block and parameter bounds.

    Attributes:
        name: a joint effect (``coulomb`` .. ``gain``), ``payload``, ``absent_part``,
            ``link_mass`` or ``inertial``.
        joint: 0-based joint for a joint effect, None for an arm-wide one.
        columns: shape (S, n, p).
        params: the parameter names (p).
        units: their units.
        lower, upper: bounds, shape (p,).
        detail: a fixed setting (the Stribeck speed), the part or link's name, or "".
    """

    name: str
    joint: int | None
    columns: F64
    params: tuple[str, ...]
    units: tuple[str, ...]
    lower: F64
    upper: F64
    detail: str = ""
    basis: tuple[F64, F64] | None = None  # "inertial": (V, scale) of eq. R4
    full: F64 | None = None  # "inertial": the full regressor Y (S, n, 10 B) of eq. R2

    @property
    def key(self) -> str:
        j = "" if self.joint is None else f"_j{self.joint + 1}"
        return f"{self.name}{j}{'@' + self.detail if self.detail else ''}"

    @property
    def label(self) -> str:
        where = "arm" if self.joint is None else f"joint {self.joint + 1}"
        return f"{self.name} ({where}{', ' + self.detail if self.detail else ''})"
