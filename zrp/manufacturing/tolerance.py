"""Tolerances of the geometric parameters, and random robots drawn within them.

Every geometric parameter of :mod:`zrp.kinematics.identification` (body-vector components
b{k}.x/y/z in the model's length unit, axis tilts u{k}.t1/t2 in rad, optionally joint offsets)
gets a tolerance ``tol_i`` (:class:`Tolerances`). A *robot* is one draw of all parameters
(:func:`draw_parameters`):

* ``"uniform"``: dx_i ~ U(-tol_i, tol_i) (tol is the half-width);
* ``"normal"``: dx_i ~ N(0, (tol_i / 3)^2) (tol is three standard deviations).

What the draws do along a trajectory is in :mod:`.population` (Monte Carlo), the first-order
budget in :mod:`.budget`, and the search for tolerances meeting a requirement in
:mod:`.allocation`.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Mapping
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.identification import parameter_space
from zrp.manufacturing._checks import (
    DISTRIBUTIONS,
    check_distribution,
    check_percentile,
    nonnegative,
)
from zrp.model.manipulator import MAX_LENGTH, Manipulator

__all__ = ["DISTRIBUTIONS", "Tolerances", "draw_parameters", "percentile_ci",
           "percentile_ci_ranks"]



@dataclass(frozen=True, eq=False)
class Tolerances:
    """Per-parameter tolerances (half-width for "uniform", 3 sigma for "normal").

    Attributes:
        values: tol_i in parameter units, shape (P,), finite and >= 0.
        names: P parameter names (:func:`zrp.kinematics.identification.parameter_names` order).
        units: P units (length unit or "rad").
        joint_offsets: whether the joint-offset parameters are included.
    """

    values: F64
    names: tuple[str, ...]
    units: tuple[str, ...]
    joint_offsets: bool = False

    def __post_init__(self) -> None:
        vals = np.array(self.values, dtype=float)
        if vals.shape != (len(self.names),) or len(self.units) != len(self.names):
            raise InputError(f"Tolerances.values: expected shape ({len(self.names)},) matching "
                             f"the names and units, got {vals.shape}")
        # an angle beyond pi or a length beyond the model's bound only overflows the sums
        limit = np.where(np.array(self.units) == "rad", np.pi, MAX_LENGTH)
        bad = ~(vals >= 0) | ~(vals <= limit)
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"tolerance of {self.names[i]}: expected a finite value from 0 to "
                             f"{limit[i]:g} ({self.units[i]}), got {vals[i]!r}")
        vals.setflags(write=False)
        object.__setattr__(self, "values", vals)

    @classmethod
    def build(cls, model: Manipulator, *, length: float = 0.0, angle_rad: float = 0.0,
              offset: float = 0.0, per_parameter: Mapping[str, float] | None = None,
              joint_offsets: bool = False) -> Tolerances:
        """Global tolerances with per-parameter overrides.

        Args:
            length: tolerance of every body-vector component (model length unit).
            angle_rad: tolerance of every axis tilt (rad).
            offset: tolerance of every joint offset (rad / length unit), if ``joint_offsets``.
            per_parameter: {name or glob pattern: tolerance}, applied in order after the
                globals, e.g. ``{"b1.*": 0, "u2.*": 2e-4}``. Names: ``b{k}.x|y|z``,
                ``u{k}.t1|t2``, ``q{k}.offset``.
        """
        space = parameter_space(model, joint_offsets=joint_offsets)
        length = nonnegative(length, "length", model.length_unit)
        angle_rad = nonnegative(angle_rad, "angle_rad", "rad")
        offset = nonnegative(offset, "offset", "rad or length unit")
        vals = np.where(np.array(space.kind) == "body", length,
                        np.where(np.array(space.kind) == "tilt", angle_rad, offset))
        for pattern, tol in (per_parameter or {}).items():
            hits = [i for i, nm in enumerate(space.names) if fnmatch.fnmatchcase(nm, pattern)]
            if not hits:
                raise InputError(
                    f"tolerance {pattern!r}: matches no parameter of {model.name!r}; expected a "
                    f"name or pattern such as b3.x, b3.*, u2.t1, u*.* (parameters: "
                    f"{space.names[0]} .. {space.names[-1]})")
            vals[hits] = nonnegative(tol, f"tolerance {pattern!r}", "parameter unit")
        return cls(vals, space.names, space.units, joint_offsets)

    def scaled(self, factor: float) -> Tolerances:
        return Tolerances(self.values * factor, self.names, self.units, self.joint_offsets)

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}

    def equivalent_mm(self, angle_scale_mm: float) -> F64:
        """Length-equivalent tolerances: angles times ``angle_scale_mm``, shape (P,)."""
        scale = np.where(np.array(self.units) == "rad", angle_scale_mm, 1.0)
        return self.values * scale

    def looseness(self, angle_scale_mm: float = 100.0) -> float:
        """Harmonic mean of the length-equivalent tolerances (0 if any is 0); see module doc."""
        eq = self.equivalent_mm(angle_scale_mm)
        if np.any(eq <= 0):
            return 0.0
        return float(eq.size / np.sum(1.0 / eq))


def draw_parameters(tolerances: Tolerances, n: int, distribution: str,
                    rng: np.random.Generator) -> F64:
    """Random parameter steps, shape (n, P): U(-tol, tol) or N(0, (tol/3)^2)."""
    check_distribution(distribution)
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
                         f"got {type(rng).__name__}")
    p = tolerances.values.size
    if distribution == "uniform":
        z = rng.uniform(-1.0, 1.0, size=(n, p))
    else:
        z = rng.standard_normal(size=(n, p)) / 3.0
    return z * tolerances.values


def percentile_ci_ranks(n: int, pct: float, confidence: float = 0.95) -> tuple[int, int]:
    """0-based ranks (lo, hi) of the order statistics that bound a distribution-free
    ``confidence`` interval of the ``pct`` percentile of ``n`` samples (normal approximation
    of the binomial count below the percentile, clipped to the sample)."""
    check_percentile(pct)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a sample size >= 1, got {n!r}")
    if not 0.0 < confidence < 1.0:
        raise InputError(f"confidence: expected 0 < confidence < 1 (e.g. 0.95), got "
                         f"{confidence!r}")
    p = pct / 100.0
    half = NormalDist().inv_cdf(0.5 + 0.5 * confidence) * np.sqrt(n * p * (1 - p))
    lo = int(np.clip(np.floor(n * p - half), 0, n - 1))
    hi = int(np.clip(np.ceil(n * p + half), 0, n - 1))
    return lo, hi


def percentile_ci(samples: ArrayLike, pct: float, confidence: float = 0.95) -> tuple[float,
                                                                                       float]:
    """Distribution-free confidence interval of a percentile from order statistics
    (:func:`percentile_ci_ranks`); ``samples`` shape (N,)."""
    x = np.sort(np.asarray(samples, dtype=float).ravel())
    if x.size == 0:
        raise InputError("samples: expected at least one value")
    lo, hi = percentile_ci_ranks(int(x.size), pct, confidence)
    return float(x[lo]), float(x[hi])
