"""A circle placement for the paper's PUMA and the 48 joint-axis cells it predicts.

The paper never gives its circle's start configuration, plane, centre or orientation law. A
:class:`CirclePlacement` names one choice of them; :func:`placement_path` solves its nominal
inverse kinematics and :func:`joint_axis_cells` the 48 joint-axis cells of Tables 2 and 3
(JE1-JE6 at xi = 0.02, 0.05, 0.07, 0.1 %) that the inverse problem of :mod:`.inverse` fits.

Unknowns (the vector of :meth:`CirclePlacement.vector`, 9 numbers):

* q0 (6 joint values, deg): the start configuration; the circle starts at FK(q0);
* the plane's normal n, as azimuth and elevation (deg) in the base frame;
* psi (deg): the direction from the start point to the centre, in the plane: toward =
  cos(psi) e1 + sin(psi) e2 with e1 = unit(n x z) (unit(n x x) when n is vertical), e2 = n x e1.

The radius is the paper's 125 mm; the orientation law is discrete: ``held`` (the hand keeps its
start orientation) or ``turning`` (the hand turns with the travel angle phi(t) about the
circle's normal, R(t) = Rot(n, phi(t)) R(0), as a tool following the circle would).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError, ZRPError
from zrp.kinematics.forward import end_effector_pose
from zrp.kinematics.ik import track_trajectory
from zrp.kinematics.trajectory import Circle, TimeLaw
from zrp.manufacturing.study import JointPath, one_at_a_time
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.paper.choices import ORIENTATION_LAWS
from zrp.paper.published import (
    JE_PARAMS,
    LIKELY_TYPOS,
    PUBLISHED_ROWS,
    PUBLISHED_TABLE2,
    PUBLISHED_TABLE3,
)
from zrp.rotations.rodrigues import er_from_axis_angle, er_multiply

__all__ = [
    "CELL_LABELS",
    "DEFAULT_PLACEMENT",
    "ORIENTATION_LAWS",
    "PUBLISHED_JE_CELLS",
    "RECOVERED",
    "RECOVERED_ALTERNATIVES",
    "TYPO_MASK",
    "UNKNOWNS",
    "CirclePlacement",
    "joint_axis_cells",
    "placement_path",
]

#: Names and units of the 9 continuous unknowns, in the order of :meth:`CirclePlacement.vector`.
UNKNOWNS = ("q1_0 (deg)", "q2_0 (deg)", "q3_0 (deg)", "q4_0 (deg)", "q5_0 (deg)", "q6_0 (deg)",
            "normal azimuth (deg)", "normal elevation (deg)", "psi, start to centre (deg)")
#: The 48 cells, in order: Table 2 JE1..JE6 x rows, then Table 3 JE1..JE6 x rows.
CELL_LABELS: tuple[tuple[int, str, float], ...] = tuple(
    (tab, col, xi) for tab in (2, 3) for col in JE_PARAMS for xi in PUBLISHED_ROWS)
#: The published values of :data:`CELL_LABELS` (Table 2 in mm, Table 3 eq (15)), as printed.
PUBLISHED_JE_CELLS: F64 = np.array(
    [(PUBLISHED_TABLE2 if tab == 2 else PUBLISHED_TABLE3)[col][PUBLISHED_ROWS.index(xi)]
     for tab, col, xi in CELL_LABELS])
#: True for the two likely typos (left out of the fit, reported beside it).
TYPO_MASK = np.array([lab in LIKELY_TYPOS for lab in CELL_LABELS])


def _in_plane_basis(normal: F64) -> tuple[F64, F64]:
    """e1, e2 spanning the plane of the unit ``normal`` (see the module docstring)."""
    e1 = np.cross(normal, [0.0, 0.0, 1.0])
    if np.linalg.norm(e1) < 1e-9:
        e1 = np.cross(normal, [1.0, 0.0, 0.0])
    e1 = e1 / np.linalg.norm(e1)
    return e1, np.cross(normal, e1)


@dataclass(frozen=True)
class CirclePlacement:
    """One placement of the paper's 125 mm circle.

    Attributes:
        q0_deg: start configuration, 6 joint values (deg).
        azimuth_deg, elevation_deg: the plane normal n = (cos el cos az, cos el sin az, sin el).
        psi_deg: direction from the start point to the centre, in the plane (deg).
        orientation: "held" or "turning" (module docstring).
        radius_mm: mm. duration_s: s (the deviations do not depend on it).
    """

    q0_deg: tuple[float, ...]
    azimuth_deg: float
    elevation_deg: float
    psi_deg: float
    orientation: str = "held"
    radius_mm: float = 125.0
    duration_s: float = 4.0

    def __post_init__(self) -> None:
        q0 = tuple(float(v) for v in self.q0_deg)
        if len(q0) != 6 or not np.all(np.isfinite(q0)):
            raise InputError(f"q0_deg: expected 6 finite joint values (deg), got {self.q0_deg!r}")
        object.__setattr__(self, "q0_deg", q0)
        if self.orientation not in ORIENTATION_LAWS:
            raise InputError(f"orientation: expected one of {ORIENTATION_LAWS}, got "
                             f"{self.orientation!r}")
        for name in ("azimuth_deg", "elevation_deg", "psi_deg", "radius_mm", "duration_s"):
            if not np.isfinite(getattr(self, name)):
                raise InputError(f"{name}: expected a finite number, got {getattr(self, name)!r}")
        if self.radius_mm <= 0 or self.duration_s <= 0:
            raise InputError("radius_mm, duration_s: expected positive values")

    def vector(self) -> F64:
        """The 9 unknowns of :data:`UNKNOWNS`, shape (9,)."""
        return np.array([*self.q0_deg, self.azimuth_deg, self.elevation_deg, self.psi_deg])

    @classmethod
    def from_vector(cls, x: ArrayLike, orientation: str = "held") -> CirclePlacement:
        """Inverse of :meth:`vector`; angles wrapped into (-180, 180] deg."""
        v = np.asarray(x, dtype=float)
        if v.shape != (9,):
            raise InputError(f"x: expected shape (9,), got {v.shape}")
        w = (v + 180.0) % 360.0 - 180.0
        return cls(tuple(w[:6]), float(w[6]), float(np.clip(v[7], -90.0, 90.0)), float(w[8]),
                   orientation)

    @property
    def normal(self) -> F64:
        """Unit normal of the circle's plane, shape (3,)."""
        az, el = np.radians(self.azimuth_deg), np.radians(self.elevation_deg)
        return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    @property
    def toward(self) -> F64:
        """Unit direction from the start point to the centre, shape (3,)."""
        e1, e2 = _in_plane_basis(self.normal)
        psi = np.radians(self.psi_deg)
        return np.cos(psi) * e1 + np.sin(psi) * e2

    def describe(self, model: Manipulator | None = None) -> dict[str, object]:
        """Start point, centre, normal and orientation law as plain values (mm, deg)."""
        model = load_model("puma") if model is None else model
        p0, _ = end_effector_pose(model, np.radians(self.q0_deg))
        return {"q0_deg": [round(v, 3) for v in self.q0_deg],
                "start_mm": [round(float(v), 2) for v in p0],
                "centre_mm": [round(float(v), 2) for v in p0 + self.radius_mm * self.toward],
                "normal": [round(float(v), 4) for v in self.normal],
                "orientation": self.orientation, "radius_mm": self.radius_mm}

    def trajectory(self, model: Manipulator) -> Circle:
        """The circle through FK(q0) with this plane, centre direction and orientation law."""
        q0 = np.radians(self.q0_deg)
        p0, er0 = end_effector_pose(model, q0)
        n = self.normal
        law = None
        if self.orientation == "turning":
            duration, time_law = self.duration_s, TimeLaw("quintic")

            def law(t: F64) -> tuple[F64, F64]:
                s, ds, _ = time_law(np.asarray(t, dtype=float) / duration)
                phi, dphi = 2.0 * np.pi * s, 2.0 * np.pi * ds / duration
                er = er_multiply(er_from_axis_angle(n, phi[:, None]), er0)
                return er, dphi[:, None] * n
        return Circle.from_start(p0, self.radius_mm, n, self.toward, duration=self.duration_s,
                                 orientation=law)


def placement_path(placement: CirclePlacement, steps: int = 360,
                   model: Manipulator | None = None) -> JointPath:
    """Nominal inverse kinematics of ``placement`` on the Table 1 PUMA (``steps`` steps).

    Raises:
        ZRPError: the circle leaves the workspace or cannot be tracked within 1e-6 mm
            (:class:`zrp.errors.UnreachableError`, :class:`zrp.errors.InputError`).
    """
    model = load_model("puma") if model is None else model
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ik = track_trajectory(model, placement.trajectory(model), np.radians(placement.q0_deg),
                              steps, warn=False)
    err = float(np.max(ik.position_error))
    if not np.isfinite(err) or err > 1e-6:
        raise InputError(f"placement: the circle is tracked only within {err:.3g} mm (damped "
                         "near a singularity); expected <= 1e-6 mm")
    return JointPath.from_ik(ik, f"{placement.radius_mm:g} mm circle ({placement.orientation}"
                                 f" orientation), {steps} steps")


def joint_axis_cells(path: JointPath, model: Manipulator | None = None) -> F64:
    """The 48 cells of :data:`CELL_LABELS` along ``path``: max delta_p (mm, Table 2) and max
    delta_R (eq 15, Table 3) of JE1-JE6 at the published levels, shape (48,)."""
    model = load_model("puma") if model is None else model
    st = one_at_a_time(model, path, JE_PARAMS, PUBLISHED_ROWS)
    return np.concatenate([st.max_delta_p.ravel(), st.max_delta_r.ravel()])


def evaluate_placement(placement: CirclePlacement, steps: int = 360) -> F64 | None:
    """:func:`joint_axis_cells` of ``placement``, or None when it cannot be tracked."""
    try:
        return joint_axis_cells(placement_path(placement, steps))
    except ZRPError:
        return None


#: The default circle of :func:`zrp.paper.scenario.puma_circle` as a placement (it reproduces
#: the default study to 1e-11, tested).
DEFAULT_PLACEMENT = CirclePlacement((0.0, 0.0, 0.0, 0.0, 90.0, 0.0), 0.0, 0.0, -90.0, "held")

#: The circle recovered from the 46 non-typo joint-axis cells of Tables 2-3 by
#: :func:`zrp.paper.inverse.recover_circle` (seed 0, popsize 15, 120 generations per law,
#: 6 polished starts per law; 67,392 placements, 516 s on the shared 2-core machine): RMS of
#: ln(ours / published) 0.13 %, every cell within 0.45 %, 41 of 48 to the printed digits;
#: the two typos come out at 0.100 and 9.995 x the printed values. Start (472.7, -204.2,
#: -244.5) mm, centre (467.6, -267.0, -136.6) mm, normal (0.812, -0.521, -0.264); the hand
#: turns once about the normal with the travel angle.
RECOVERED = CirclePlacement(
    (-167.28698575668648, -136.90637950538823, 147.73232440618762, 87.4002609637351,
     22.822018666671227, -154.43096604202347),
    -32.68017198938344, -15.314265091829341, -63.568628974847854, "turning")

#: Other polished starts of the same search that also reproduce all 46 cells within 5 %
#: (RMS 0.34-1.09 %), rounded to 0.1 deg: (q0 deg, azimuth, elevation, psi). Their spread
#: is how loosely the tables pin each unknown (README.md in this folder).
RECOVERED_ALTERNATIVES: tuple[tuple[tuple[float, ...], float, float, float], ...] = (
    ((160.7, -127.5, 147.4, -155.7, 35.4, 85.2), -57.2, -17.4, 9.0),
    ((167.0, -134.8, 147.2, 138.3, 12.5, -40.7), -54.6, -16.7, -38.9),
    ((-174.1, -143.9, 143.9, 39.3, 57.8, -156.7), -66.3, -28.6, -126.8),
    ((176.8, -135.6, 148.2, -121.6, 10.4, -134.4), 50.1, -19.7, -116.6),
    ((177.8, -132.8, 147.9, 178.0, 24.5, -150.5), 52.3, -20.1, -146.8),
)
