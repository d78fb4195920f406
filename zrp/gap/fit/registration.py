"""The full registration of a fit: where the robot's base sits in the instrument frame and
where the measured points sit on the tool, with robust 95 % intervals.

The fit estimates a small rotation phi on top of a starting rotation R_b0 (the Kabsch
solution); the reported rotation is the whole R_b = exp([phi]) R_b0 (instrument-from-base:
m = R_b x_base + t_b), as a rotation vector (Euler-Rodrigues, :mod:`zrp.rotations`) and as
Z-Y-X angles (yaw, pitch, roll: R_b = R_z(yaw) R_y(pitch) R_x(roll)). Intervals of these
nonlinear functions of phi come from the delta method (central differences of the function
with respect to phi, step 1e-6 rad, propagated through the covariance of phi).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.leastsq import Z95, FitResult
from zrp.jsonio import dict_from_dataclass
from zrp.rotations import er_from_matrix, matrix_from_rotvec, rotvec_from_er

__all__ = ["Quantity", "Registration", "registration_of"]



@dataclass(frozen=True)
class Quantity:
    """A reported value with its standard error and 95 % interval."""

    name: str
    unit: str
    value: float
    stderr: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise InputError(f"Quantity {self.name}: value {self.value} is not finite")

    @property
    def ci95(self) -> tuple[float, float]:
        h = Z95 * self.stderr
        return (self.value - h, self.value + h)

    def to_dict(self) -> dict[str, Any]:
        fin = math.isfinite(self.stderr)
        return {"name": self.name, "unit": self.unit, "value": self.value,
                "stderr": self.stderr if fin else None,
                "ci95": list(self.ci95) if fin else None}


@dataclass(frozen=True)
class Registration:
    """Instrument-from-base transform and tool points (length unit of the model).

    Attributes:
        frame: "instrument" (the transform was estimated) or "base" (identity, not fitted).
        rotation: R_b, shape (3, 3).
        rotvec: rotation vector of R_b (x, y, z, angle), rad.
        zyx: yaw, pitch, roll of R_b, rad.
        translation: t_b (x, y, z).
        tool_points: per measured point label, (x, y, z) in the flange's zero-reference frame.
    """

    frame: str
    rotation: F64
    rotvec: tuple[Quantity, ...]
    zyx: tuple[Quantity, ...]
    translation: tuple[Quantity, ...]
    tool_points: dict[str, tuple[Quantity, ...]]

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self, rename={"rotation": "rotation_matrix",
                                                 "rotvec": "rotation_vector",
                                                 "zyx": "zyx_angles"})


def _zyx(r: F64) -> F64:
    return np.array([math.atan2(r[1, 0], r[0, 0]), -math.asin(max(-1.0, min(1.0, r[2, 0]))),
                     math.atan2(r[2, 1], r[2, 2])])


def _rotvec4(r: F64) -> F64:
    rv = rotvec_from_er(er_from_matrix(r))
    return np.append(rv, np.linalg.norm(rv))


def _delta(fn: Callable[[F64], F64], phi: F64, rb0: F64, cov: F64) -> tuple[F64, F64]:
    """Value of fn(exp([phi]) R_b0) and its standard errors by the delta method."""
    val = fn(matrix_from_rotvec(phi) @ rb0)
    h = 1e-6
    cols = []
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        cols.append((fn(matrix_from_rotvec(phi + e) @ rb0)
                     - fn(matrix_from_rotvec(phi - e) @ rb0)) / (2 * h))
    D = np.stack(cols, axis=1)
    if not np.all(np.isfinite(cov)):
        return val, np.full(val.shape, np.inf)
    return val, np.sqrt(np.clip(np.einsum("ij,jk,ik->i", D, cov, D), 0.0, None))


def registration_of(fit: FitResult, stderr: F64, cov: F64, labels: tuple[str, ...],
                    length_unit: str) -> Registration:
    """The registration of ``fit`` with the standard errors ``stderr`` (p,) and covariance
    ``cov`` (p, p) of its parameters (robust ones from :mod:`zrp.gap.fit.uncertainty`)."""
    idx = {s.name: i for i, s in enumerate(fit.specs)}
    rb0 = np.asarray(fit.base_rotation, dtype=float)

    def q(name: str, unit: str, default: float = 0.0) -> Quantity:
        i = idx.get(name)
        if i is None:  # not fitted (base-frame data, or structurally unidentifiable)
            return Quantity(name, unit, default, math.nan)
        return Quantity(name, unit, float(fit.theta[i]), float(stderr[i]))

    tools = {lab: tuple(q(f"tool[{lab}].{c}", length_unit) for c in "xyz") for lab in labels}
    if "base.rx" not in idx:
        zero = tuple(Quantity(n, "rad", 0.0, 0.0) for n in ("yaw", "pitch", "roll"))
        return Registration("base", np.eye(3), (), zero,
                            tuple(Quantity(f"t.{c}", length_unit, 0.0, 0.0) for c in "xyz"),
                            tools)
    ir = [idx[f"base.r{c}"] for c in "xyz"]
    phi = fit.theta[ir]
    cphi = cov[np.ix_(ir, ir)]
    rv, rv_se = _delta(_rotvec4, phi, rb0, cphi)
    ang, ang_se = _delta(_zyx, phi, rb0, cphi)
    rot = tuple(Quantity(n, "rad", float(v), float(s)) for n, v, s in
                zip(("rotation_vector.x", "rotation_vector.y", "rotation_vector.z", "angle"),
                    rv, rv_se, strict=True))
    zyx = tuple(Quantity(n, "rad", float(v), float(s)) for n, v, s in
                zip(("yaw", "pitch", "roll"), ang, ang_se, strict=True))
    trans = tuple(Quantity(f"t.{c}", length_unit, float(fit.theta[idx[f"base.t{c}"]]),
                           float(stderr[idx[f"base.t{c}"]])) for c in "xyz")
    return Registration("instrument", matrix_from_rotvec(phi) @ rb0, rot, zyx, trans, tools)
