"""The options of a diagnosis, validated once, with messages naming the API argument."""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arguments import check_float, check_int
from zrp.errors import InputError
from zrp.gap.data.choices import MAX_WITHHELD
from zrp.gap.model.choices import EFFECTS
from zrp.gap.model.domains import DEFAULT_MAX_TILT_RAD

__all__ = ["MAX_WITHHELD", "DiagnosisOptions"]



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
        max_tilt_rad: the largest axis tilt accepted (rad; default a few mrad of a machined
            part, :data:`zrp.gap.model.domains.DEFAULT_MAX_TILT_RAD`): widen it for a robot
            known to carry a larger tilt.
        residual_model: also train a learned residual term on the joint angles after the final
            model and test it on the withheld poses (:mod:`zrp.gap.analysis.residual`).

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
    max_tilt_rad: float = DEFAULT_MAX_TILT_RAD
    residual_model: bool = False

    def __post_init__(self) -> None:
        bad = [e for e in self.effects if e not in EFFECTS]
        if bad:
            raise InputError(f"effects: unknown {', '.join(bad)}; valid: {', '.join(EFFECTS)}")
        check_float(self.withheld_fraction, "withheld_fraction", 0.0, MAX_WITHHELD,
                    open_lo=True)
        check_int(self.folds, "folds", 2, 100)
        check_float(self.alpha, "alpha", 0.0, 1.0, open_lo=True, open_hi=True)
        check_float(self.min_gain, "min_gain", 0.0, 1.0, open_hi=True)
        check_int(self.max_steps, "max_steps", 1, len(EFFECTS))
        check_float(self.max_tilt_rad, "max_tilt_rad", 0.0, 0.5, open_lo=True, unit="rad")
        if not isinstance(self.residual_model, bool):
            raise InputError(f"residual_model: expected True or False, got "
                             f"{self.residual_model!r}")
        if self.noise_sigma is not None:
            check_float(self.noise_sigma, "noise_sigma", 0.0, open_lo=True, unit="length unit")
        if not self.harmonics or not all(isinstance(h, numbers.Integral) and 1 <= h <= 100
                                         for h in self.harmonics):
            raise InputError(f"harmonics: expected whole numbers 1..100, got {self.harmonics}")
        try:
            g = np.asarray(self.gravity_dir, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"gravity_dir: expected a unit 3-vector, got "
                             f"{self.gravity_dir}") from exc
        if g.shape != (3,) or not np.isclose(np.linalg.norm(g), 1.0):
            raise InputError(f"gravity_dir: expected a unit 3-vector, got {self.gravity_dir}")

    def settings(self) -> dict[str, Any]:
        """The options as they appear in diagnosis.json's ``settings``."""
        return {"effects": list(self.effects), "alpha": self.alpha, "min_gain": self.min_gain,
                "max_steps": self.max_steps, "folds": self.folds,
                "harmonics": list(self.harmonics), "gravity_dir": list(self.gravity_dir),
                "max_tilt_rad": self.max_tilt_rad, "residual_model": self.residual_model}
