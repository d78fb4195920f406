"""Which mass properties the real robot has: the arm's own, or an announced fallback.

* ``"own"``: the inertias, damping and friction of the arm's shipped URDF/MJCF
  (:func:`mjcf.arm_dynamics`), the tool and everything beyond the last joint lumped into the
  last link. ``"auto"`` takes them whenever they are given.
* ``"puma560"``: the PUMA 560 literature values (:func:`mjcf.puma560_inertias`): the paper's
  PUMA's own (``"auto"`` takes them for it, :func:`is_paper_puma`), or the fallback of
  ``"auto"`` for a 6R arm given no inertias.
* ``"rods"``: uniform rods (:func:`mjcf.rod_inertias`): the fallback for other arms.

A fallback chosen by ``"auto"`` is announced: a :class:`DynamicsFallbackWarning` and the
``dynamics`` line of :meth:`sim.robot.real.RealRobot.describe` (the truth file, the
benchmark's results).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mjcf.inertia import BodyInertia, puma560_inertias, rod_inertias
from sim.robot.model import RealRobotOptions
from zrp.errors import ZRPWarning
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = ["DynamicsFallbackWarning", "RobotMass", "is_paper_puma", "link_inertias", "robot_mass"]


class DynamicsFallbackWarning(ZRPWarning):
    """The real robot was given no inertias of its own: it borrows the PUMA 560's or rods'."""


@dataclass(frozen=True)
class RobotMass:
    """The mass model chosen.

    Attributes:
        kind: "own", "puma560" or "rods".
        fallback: True when ``"auto"`` had no inertias to take and chose ``kind`` instead.
        note: one line saying which (for reports).
    """

    kind: str
    fallback: bool
    note: str


def robot_mass(model: Manipulator, options: RealRobotOptions) -> RobotMass:
    """The mass model for ``model`` under ``options`` (module docstring); announces a fallback
    with a :class:`DynamicsFallbackWarning`."""
    kind = options.inertia
    if kind == "own" or (kind == "auto" and options.dynamics is not None):
        assert options.dynamics is not None
        return RobotMass("own", False, options.dynamics.summary())
    if kind != "auto":
        return RobotMass(kind, False, f"{kind} inertias (chosen)")
    six_r = model.n == 6 and not model.prismatic.any()
    kind = "puma560" if six_r else "rods"
    if six_r and is_paper_puma(model):
        return RobotMass(kind, False, "PUMA 560 literature inertias (the arm's own)")
    note = (f"no inertias given for {model.name!r}: the simulated robot borrows "
            + ("the PUMA 560's (literature values)" if six_r else "uniform rods'")
            + "; pass the arm's URDF/MJCF (mjcf.arm_dynamics) to simulate it as itself")
    warnings.warn(note, DynamicsFallbackWarning, stacklevel=3)
    return RobotMass(kind, True, note)


def is_paper_puma(model: Manipulator) -> bool:
    """True for the paper's Table 1 PUMA (the built-in ``puma``, in any length unit): its own
    inertias are the PUMA 560 literature values."""
    puma = load_model("puma")
    if model.n != puma.n or model.prismatic.any():
        return False
    mine = np.asarray(model.bodies) * metres_per_unit(model.length_unit, "model.length_unit")
    ref = np.asarray(puma.bodies) * metres_per_unit(puma.length_unit, "puma.length_unit")
    return bool(np.allclose(model.axes, puma.axes, atol=1e-12)
                and np.allclose(mine, ref, rtol=0, atol=1e-12))


def link_inertias(mass: RobotMass, true_model: Manipulator, options: RealRobotOptions,
                  scale: float) -> list[BodyInertia]:
    """The n links' mass properties (metres) of the chosen ``mass`` model for the real
    geometry ``true_model``."""
    if mass.kind == "own":
        assert options.dynamics is not None
        return list(options.dynamics.inertias)
    if mass.kind == "puma560":
        return puma560_inertias(true_model, scale)
    return rod_inertias(true_model, scale)
