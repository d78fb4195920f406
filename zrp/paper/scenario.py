"""The paper's numerical example: a 125 mm circle drawn by the Table 1 PUMA.

The paper gives no centre, plane, orientation law, duration or start configuration. Chosen
here (and stated in README.md):

* start configuration q0 = (0, 0, 0, 0, 90, 0) deg: q = 0 is a wrist singularity (u_4 = -u_6),
  bending joint 5 by 90 deg moves well away from it and points the tool horizontally along +x;
* the circle lies in the vertical plane facing the tool (normal +x, the tool's axial
  direction) through the start point p0 = (558.8, 254, -431.8) mm, with its centre 125 mm
  above it (the start is the lowest point), travelled once counter-clockwise about +x;
* duration 4 s with a quintic time law (at rest at both ends), hand orientation held constant;
* 1000 integration steps (h = 4 ms).

Among start configurations and circle placements scanned, this one keeps the scaled
manipulability above 0.03 along the whole circle, so no damping is needed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.kinematics.forward import end_effector_pose
from zrp.kinematics.ik import IKResult, track_trajectory
from zrp.kinematics.trajectory import Circle
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator

__all__ = ["PUMA_Q0_DEG", "CircleSetup", "puma_circle", "puma_circle_ik"]

PUMA_Q0_DEG = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)
PUMA_RADIUS_MM = 125.0
PUMA_DURATION_S = 4.0


@dataclass(frozen=True, eq=False)
class CircleSetup:
    """A model, a trajectory and the start configuration q0 (shape (n,), rad)."""

    model: Manipulator
    trajectory: Circle
    q0: NDArray[np.float64]


def puma_circle(
    model: Manipulator | None = None,
    *,
    radius_mm: float = PUMA_RADIUS_MM,
    duration_s: float = PUMA_DURATION_S,
    time_law: str = "quintic",
) -> CircleSetup:
    """The default circle for the Table 1 PUMA (or a perturbed copy of it, same q0)."""
    model = load_model("puma") if model is None else model
    q0 = np.radians(PUMA_Q0_DEG)
    p0, _ = end_effector_pose(model, q0)
    circle = Circle.from_start(p0, radius_mm, normal=[1.0, 0.0, 0.0], toward=[0.0, 0.0, 1.0],
                               duration=duration_s, time_law=time_law)
    return CircleSetup(model, circle, q0)


def puma_circle_ik(steps: int = 1000, **kwargs: object) -> IKResult:
    """Nominal inverse kinematics of :func:`puma_circle` with ``steps`` integration steps."""
    setup = puma_circle()
    return track_trajectory(setup.model, setup.trajectory, setup.q0, steps, **kwargs)  # type: ignore[arg-type]
