"""How large the errors are: 3-D position errors of a point set, and the noise floor."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.leastsq import point_errors
from zrp.jsonio import dict_from_dataclass

__all__ = ["CHI3_P95", "NOISE_METHODS", "Metrics", "NoiseFloor"]

F64 = NDArray[np.float64]
#: 95th percentile of |r| for isotropic Gaussian noise, in units of sigma (chi, 3 dof).
CHI3_P95 = 2.7954834829151074
NOISE_METHODS = ("rigid_links", "repeats", "given", "none")


@dataclass(frozen=True)
class Metrics:
    """3-D position errors |r| of a set of measured points (length unit).

    Attributes:
        rms: sqrt(mean |r|^2).
        p95: 95th percentile of |r|.
        max: largest |r|.
        n_points: number of measured points.
    """

    rms: float
    p95: float
    max: float
    n_points: int

    def __post_init__(self) -> None:
        vals = (self.rms, self.p95, self.max)
        if self.n_points < 1 or not all(math.isfinite(v) and v >= 0 for v in vals):
            raise InputError(f"Metrics: expected finite non-negative errors over >= 1 point, "
                             f"got rms={self.rms}, p95={self.p95}, max={self.max}, "
                             f"n_points={self.n_points}")

    @classmethod
    def of(cls, residual: F64) -> Metrics:
        e = point_errors(residual)
        return cls(float(np.sqrt(np.mean(e**2))), float(np.percentile(e, 95)), float(e.max()),
                   int(e.size))

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


@dataclass(frozen=True)
class NoiseFloor:
    """Measurement-noise estimate.

    Attributes:
        sigma: per-coordinate standard deviation (length unit), or None when the data allow no
            estimate.
        method: "rigid_links" (mutual distances of points measured in the same pose),
            "repeats" (poses measured more than once), "given" or "none".
        n_samples: number of distances or repeated coordinates it rests on.
        detail: per-pair or per-method numbers for the report.
    """

    sigma: float | None
    method: str
    n_samples: int = 0
    detail: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.method not in NOISE_METHODS:
            raise InputError(f"NoiseFloor.method: {self.method!r} not in {NOISE_METHODS}")
        if (self.sigma is None) != (self.method == "none"):
            raise InputError("NoiseFloor: sigma must be None exactly when method is 'none'")
        if self.sigma is not None and not (math.isfinite(self.sigma) and self.sigma >= 0):
            raise InputError(f"NoiseFloor.sigma: expected a finite value >= 0, got {self.sigma}")

    @property
    def rms(self) -> float | None:
        """Expected 3-D RMS of pure noise, sqrt(3) sigma."""
        return None if self.sigma is None else math.sqrt(3.0) * self.sigma

    @property
    def p95(self) -> float | None:
        return None if self.sigma is None else CHI3_P95 * self.sigma

    def to_dict(self) -> dict[str, Any]:
        return {"sigma": self.sigma, "rms": self.rms, "p95": self.p95,
                **dict_from_dataclass(self, exclude=("sigma",))}
