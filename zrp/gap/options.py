"""The options of a diagnosis, validated once, with messages naming the API argument."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.errors import InputError
from zrp.gap.effects import EFFECTS

__all__ = ["DiagnosisOptions"]


@dataclass(frozen=True)
class DiagnosisOptions:
    """How :func:`zrp.gap.diagnose` searches (the arguments of the same names).

    Attributes:
        effects: candidate effects (subset of :data:`zrp.gap.EFFECTS`), tried in this order.
        withheld_fraction: share of the (distinct) poses withheld from fitting and selection.
        folds: cross-validation folds within the fitting poses (used for ranking).
        alpha: significance level of the F test that admits an effect; joint groups are kept
            when their Wald p-value is below alpha / (number of groups).
        min_gain: an effect must lower the cross-validated RMS by at least this fraction.
        max_steps: most effects added (>= 1).
        noise_sigma: known per-coordinate instrument noise (length unit), or None to estimate
            it from the data.
        harmonics: harmonics of ``cyclic_error``.
        gravity_dir: gravity direction in the base frame (lumped-mass compliance model).
        progress: show a progress bar.

    Raises:
        InputError: naming the argument at fault.
    """

    effects: tuple[str, ...] = EFFECTS
    withheld_fraction: float = 0.25
    folds: int = 5
    alpha: float = 1e-3
    min_gain: float = 0.01
    max_steps: int = 4
    noise_sigma: float | None = None
    harmonics: tuple[int, ...] = (1, 2)
    gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0)
    progress: bool = False

    def __post_init__(self) -> None:
        bad = [e for e in self.effects if e not in EFFECTS]
        if bad:
            raise InputError(f"effects: unknown {', '.join(bad)}; valid: {', '.join(EFFECTS)}")
        if not 0.0 < self.withheld_fraction < 1.0:
            raise InputError(f"withheld_fraction: expected a value in (0, 1), got "
                             f"{self.withheld_fraction}")
        if int(self.folds) != self.folds or self.folds < 2:
            raise InputError(f"folds: expected at least 2 cross-validation folds, got "
                             f"{self.folds}")
        if not 0.0 < self.alpha < 1.0:
            raise InputError(f"alpha: expected a significance level in (0, 1), got "
                             f"{self.alpha}")
        if not 0.0 <= self.min_gain < 1.0:
            raise InputError(f"min_gain: expected a fraction in [0, 1), got {self.min_gain}")
        if int(self.max_steps) != self.max_steps or self.max_steps < 1:
            raise InputError(f"max_steps: expected a whole number >= 1, got {self.max_steps}")
        if self.noise_sigma is not None and not (self.noise_sigma > 0
                                                 and math.isfinite(self.noise_sigma)):
            raise InputError(f"noise_sigma: expected a positive number (length unit), got "
                             f"{self.noise_sigma}")
        if not self.harmonics or any(int(h) != h or h < 1 for h in self.harmonics):
            raise InputError(f"harmonics: expected positive integers, got {self.harmonics}")
        g = np.asarray(self.gravity_dir, dtype=float)
        if g.shape != (3,) or not np.isclose(np.linalg.norm(g), 1.0):
            raise InputError(f"gravity_dir: expected a unit 3-vector, got {self.gravity_dir}")

    def settings(self) -> dict[str, Any]:
        """The options as they appear in diagnosis.json's ``settings``."""
        return {"effects": list(self.effects), "alpha": self.alpha, "min_gain": self.min_gain,
                "max_steps": self.max_steps, "folds": self.folds,
                "harmonics": list(self.harmonics), "gravity_dir": list(self.gravity_dir)}
