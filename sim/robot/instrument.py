"""The laser tracker that measures the "real" robot: its noise and where it stands
(:class:`Instrument`), and a random placement of it (:func:`random_instrument`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.rotations import matrix_from_rotvec
from zrp.units import units_per_mm

__all__ = ["TRACKER_NOISE_RANGE_MM", "Instrument", "check_number", "random_instrument"]



def check_number(v: object, name: str, unit: str, lo: float | None = None,
                 strict: bool = False) -> float:
    """``v`` as a finite float (``>= lo``, or ``> lo`` if ``strict``); an :class:`InputError`
    naming ``name`` and ``unit`` if not."""
    try:
        x = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {v!r}") from exc
    if not math.isfinite(x) or (lo is not None and (x <= lo if strict else x < lo)):
        cond = "" if lo is None else f" {'>' if strict else '>='} {lo:g}"
        raise InputError(f"{name}: expected a finite number{cond} ({unit}), got {v!r}")
    return x


@dataclass(frozen=True)
class Instrument:
    """The laser tracker: its noise and where it stands.

    Attributes:
        noise_sigma: isotropic Gaussian noise per coordinate, model length unit (0.01-0.03 mm
            is typical of a laser tracker at a few metres).
        rotvec: rotation vector of the instrument-from-base rotation, rad, shape (3,).
        translation: base origin in the instrument frame, model length unit, shape (3,).
    """

    noise_sigma: float = 0.02
    rotvec: tuple[float, float, float] = (0.01, -0.02, 2.4)
    translation: tuple[float, float, float] = (2500.0, 800.0, 300.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "noise_sigma", check_number(self.noise_sigma, "noise_sigma",
                                                     "length unit", 0.0))
        for name in ("rotvec", "translation"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise InputError(f"{name}: expected 3 finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in a))

    @property
    def rotation(self) -> F64:
        """Instrument-from-base rotation, shape (3, 3)."""
        return matrix_from_rotvec(self.rotvec)


#: The range of laser-tracker noise per coordinate the simulations draw from, mm.
TRACKER_NOISE_RANGE_MM = (0.01, 0.03)


def random_instrument(model: Manipulator, rng: np.random.Generator,
                      noise_sigma: float | tuple[float, float] | None = None) -> Instrument:
    """A tracker 1.2-2.4 reaches away in a random direction, turned about the vertical at
    random and levelled within 0.02 rad; noise drawn uniformly from ``noise_sigma`` (a range,
    or one value, model length unit; None: :data:`TRACKER_NOISE_RANGE_MM` in the model's
    unit)."""
    if noise_sigma is None:
        per_mm = units_per_mm(model.length_unit, "model.length_unit")
        noise_sigma = (TRACKER_NOISE_RANGE_MM[0] * per_mm, TRACKER_NOISE_RANGE_MM[1] * per_mm)
    lo, hi = (noise_sigma, noise_sigma) if np.isscalar(noise_sigma) else noise_sigma  # type: ignore[misc]
    sigma = float(rng.uniform(float(lo), float(hi)))
    rot = np.array([*rng.uniform(-0.02, 0.02, 2), rng.uniform(-math.pi, math.pi)])
    ang = rng.uniform(-math.pi, math.pi)
    dist = rng.uniform(1.2, 2.4) * model.reach
    trans = np.array([dist * math.cos(ang), dist * math.sin(ang),
                      rng.uniform(-0.3, 0.3) * model.reach])
    return Instrument(sigma, tuple(rot), tuple(trans))  # type: ignore[arg-type]
