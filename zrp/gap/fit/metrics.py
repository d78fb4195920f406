"""How large the errors are: 3-D position errors of a point set (the noise floor is
:class:`zrp.gap.data.noise.NoiseFloor`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.leastsq import point_errors
from zrp.jsonio import dict_from_dataclass

__all__ = ["Metrics"]



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
