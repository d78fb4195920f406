"""The paper's numerical example: a 125 mm circle drawn by the Table 1 PUMA.

The paper gives no centre, plane, orientation law, duration or start configuration. Chosen
here (and stated in README.md in this folder):

* start configuration q0 = (0, 0, 0, 0, 90, 0) deg: q = 0 is a wrist singularity (u_4 = -u_6),
  bending joint 5 by 90 deg moves well away from it and points the tool horizontally along +x;
* the circle lies in the vertical plane facing the tool (normal +x, the tool's axial
  direction) through the start point p0 = (558.8, 254, -431.8) mm, with its centre 125 mm
  above it (the start is the lowest point), travelled once counter-clockwise about +x;
* duration 4 s with a quintic time law (at rest at both ends), hand orientation held constant;
* 1000 integration steps (h = 4 ms).

Among start configurations and circle placements scanned, this one keeps the scaled
manipulability above 0.03 along the whole circle, so no damping is needed.

The start configuration is the scenario's, not the library's: :func:`circle_joint_path` (the
same circle construction for any arm, as used by ``zrp study`` / ``zrp tolerance``) defaults
to it only for the paper's Table 1 PUMA (:func:`is_paper_model`) and needs ``q0`` otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, end_effector_pose, forward_kinematics
from zrp.kinematics.ik import IKResult, track_trajectory
from zrp.kinematics.trajectory import Circle
from zrp.manufacturing.study import JointPath
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.paper.choices import PUMA_DURATION_S, PUMA_Q0_DEG, PUMA_RADIUS_MM

__all__ = [
    "PUMA_DURATION_S",
    "PUMA_Q0_DEG",
    "PUMA_RADIUS_MM",
    "CircleSetup",
    "circle_joint_path",
    "is_paper_model",
    "paper_start",
    "puma_circle",
    "puma_circle_ik",
]



@dataclass(frozen=True, eq=False)
class CircleSetup:
    """A model, a trajectory and the start configuration q0 (shape (n,), rad)."""

    model: Manipulator
    trajectory: Circle
    q0: F64


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


def is_paper_model(model: Manipulator) -> bool:
    """Whether ``model`` has the geometry of the paper's Table 1 PUMA (the published tables
    and the default start configuration apply only to it)."""
    puma = load_model("puma")
    return (model.n == puma.n and not model.prismatic.any()
            and np.allclose(model.axes, puma.axes, atol=1e-9)
            and np.allclose(model.bodies, puma.bodies, atol=1e-9))


def paper_start(model: Manipulator) -> F64:
    """The start configuration q0 (rad) chosen for the paper's PUMA, :data:`PUMA_Q0_DEG`.

    Raises:
        InputError: naming ``q0`` when ``model`` is not the paper's Table 1 PUMA: other arms
            have no default start configuration.
    """
    if not is_paper_model(model):
        raise InputError(f"q0: required for {model.name!r} ({model.n} joints): the default "
                         f"start configuration {PUMA_Q0_DEG} deg is the paper's, for its Table 1"
                         f" PUMA only; pass q0 = the start joint values, shape ({model.n},) "
                         "(rad / length unit)")
    return np.radians(PUMA_Q0_DEG)


def circle_joint_path(model: Manipulator, *, q0: ArrayLike | None = None,
                      radius: float = PUMA_RADIUS_MM, duration: float = PUMA_DURATION_S,
                      steps: int = 360, normal: ArrayLike | None = None,
                      toward: ArrayLike | None = None, time_law: str = "quintic") -> JointPath:
    """Nominal inverse kinematics of a circle through the end-effector point at ``q0``, placed
    as in the paper's example: the plane's normal is the tool's axial direction u_a at q0, the
    centre lies ``radius`` above the start (base +z projected into the plane; base +x if z is
    normal to it). For the PUMA the defaults reproduce :func:`puma_circle`.

    Args:
        q0: start configuration, shape (n,) (rad / length unit); default :func:`paper_start`
            for the paper's PUMA, required for every other model.
        radius: length unit. duration: s. steps: integration steps (T = steps + 1 samples).
        normal, toward: override the plane's normal and the direction to the centre.

    Raises:
        InputError: ``q0`` is missing for a model other than the paper's PUMA.
    """
    q0 = paper_start(model) if q0 is None else q0
    q0 = np.asarray(check_q(model, q0, "q0"), dtype=float)
    if q0.shape != (model.n,):
        raise InputError(f"q0: expected shape ({model.n},), got {q0.shape}")
    fk = forward_kinematics(model, q0)
    nrm = fk.axial if normal is None else np.asarray(normal, dtype=float)
    if toward is None:
        nn = nrm / max(float(np.linalg.norm(nrm)), 1e-300)
        z = np.array([0.0, 0.0, 1.0])
        toward = z if np.linalg.norm(z - (z @ nn) * nn) > 1e-6 else np.array([1.0, 0.0, 0.0])
    circle = Circle.from_start(fk.position, radius, nrm, toward, duration=duration,
                               time_law=time_law)
    ik = track_trajectory(model, circle, q0, steps)
    return JointPath.from_ik(ik, f"{radius:g} {model.length_unit} circle, {steps} steps, "
                                 f"{duration:g} s, {ik.method}")
