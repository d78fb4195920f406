"""How an arm is built into MJCF: :class:`MJCFOptions` and the default colours."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mjcf.inertia import INERTIA_MODELS
from zrp.errors import InputError

__all__ = [
    "BASE_RGBA",
    "FLOOR_RGBA",
    "LINK_RGBA",
    "NAME_OK",
    "PRISMATIC_RGBA",
    "REVOLUTE_RGBA",
    "RGBA",
    "MJCFOptions",
]

RGBA = tuple[float, float, float, float]

#: Default colours of the links, revolute and prismatic joint markers, base and floor.

LINK_RGBA: RGBA = (0.55, 0.62, 0.72, 1.0)
REVOLUTE_RGBA: RGBA = (0.95, 0.55, 0.15, 1.0)
PRISMATIC_RGBA: RGBA = (0.30, 0.75, 0.35, 1.0)
BASE_RGBA: RGBA = (0.35, 0.35, 0.38, 1.0)
FLOOR_RGBA: RGBA = (0.88, 0.88, 0.86, 1.0)
#: A valid MJCF element name (or name prefix).
NAME_OK = re.compile(r"^[A-Za-z_][A-Za-z0-9_.:-]*$")


def _check_rgba(value: ArrayLike, name: str) -> RGBA:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise InputError(f"{name}: expected 4 numbers in [0, 1] (r, g, b, a), got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]), float(arr[3]))


def _check_positive(value: float, name: str, unit: str, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {value!r}") from exc
    ok = v >= 0 if allow_zero else v > 0
    if not (math.isfinite(v) and ok):
        bound = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{name}: expected a finite number {bound} ({unit}), got {value!r}")
    return v


@dataclass(frozen=True)
class MJCFOptions:
    """How to build the MJCF model.

    Attributes:
        inertia: "none" (1 g placeholder bodies: kinematics only), "rods" (uniform rods and
            motor masses, any arm) or "puma560" (literature values, 6R PUMA-type arms only).
        actuators: add a PD servo per joint: a position actuator ``servo{k}`` (gain ``kp``) and,
            if ``kv > 0``, a velocity actuator ``servo{k}_rate`` (gain ``kv``). ctrl holds the
            n position set points, then the n rate set points (0 = plain damping).
        kp: position gain, N m/rad (N/m for prismatic joints).
        kv: velocity gain, N m s/rad (N s/m).
        gravity_compensation: compensate gravity on every body (MuJoCo ``gravcomp``).
        gravity: gravity vector, m/s^2, shape (3,).
        timestep: simulation step, s.
        visuals: add link capsules, joint cylinders and the end-effector triad.
        floor: add a floor and a pedestal under the base.
        alpha: opacity multiplier of every visual (e.g. 0.3 for a ghost arm).
        link_rgba: colour of the link capsules.
        tint: if given, one colour for every visual of the arm (e.g. a pale "ghost" arm).
        link_radius: capsule radius, m; None picks 2.2 % of the arm's reach.
        prefix: prefix of every element name (to put several arms in one scene).
        offscreen_size: (width, height) of MuJoCo's offscreen framebuffer, pixels.
    """

    inertia: str = "none"
    actuators: bool = False
    kp: float = 2000.0
    kv: float = 100.0
    gravity_compensation: bool = False
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    timestep: float = 1e-3
    visuals: bool = True
    floor: bool = True
    alpha: float = 1.0
    link_rgba: RGBA = LINK_RGBA
    tint: RGBA | None = None
    link_radius: float | None = None
    prefix: str = ""
    offscreen_size: tuple[int, int] = (1280, 960)

    def __post_init__(self) -> None:
        if self.inertia not in INERTIA_MODELS:
            raise InputError(f"inertia: unknown model {self.inertia!r}; expected one of "
                             f"{INERTIA_MODELS}")
        _check_positive(self.kp, "kp", "N m/rad")
        _check_positive(self.kv, "kv", "N m s/rad", allow_zero=True)
        _check_positive(self.timestep, "timestep", "s")
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputError(f"gravity: expected 3 finite numbers (m/s^2), got {self.gravity!r}")
        object.__setattr__(self, "gravity", tuple(float(x) for x in g))
        a = _check_positive(self.alpha, "alpha", "opacity in (0, 1]")
        if a > 1:
            raise InputError(f"alpha: expected an opacity in (0, 1], got {self.alpha!r}")
        object.__setattr__(self, "link_rgba", _check_rgba(self.link_rgba, "link_rgba"))
        if self.tint is not None:
            object.__setattr__(self, "tint", _check_rgba(self.tint, "tint"))
        if self.link_radius is not None:
            _check_positive(self.link_radius, "link_radius", "m")
        if self.prefix and not NAME_OK.match(self.prefix):
            raise InputError(f"prefix: {self.prefix!r} is not a valid MJCF name prefix; use "
                             f"letters, digits and _ . : -")
        size = tuple(int(x) for x in self.offscreen_size)
        if len(size) != 2 or min(size) < 1:
            raise InputError(f"offscreen_size: expected (width, height) in pixels, got "
                             f"{self.offscreen_size!r}")
        object.__setattr__(self, "offscreen_size", size)
