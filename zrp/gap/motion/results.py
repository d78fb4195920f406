"""Typed results of the motion diagnosis (:func:`zrp.gap.motion.diagnose_motion`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.leastsq import Z95
from zrp.gap.fit.metrics import Metrics
from zrp.gap.search.steps import EffectsFound
from zrp.jsonio import dict_from_dataclass

__all__ = ["MotionDiagnosis", "MotionEstimate", "MotionStep", "PhaseError"]

#: 97.5 % quantile of the standard normal (95 % two-sided intervals).


@dataclass(frozen=True)
class MotionEstimate:
    """A parameter of the final model with its 95 % normal-theory interval.

    Attributes:
        name, effect, unit: e.g. "q2.lag", "servo_lag", "s".
        joint: 1-based joint, 0 when shared by all joints.
        value, stderr: estimate and standard error (unit).
    """

    name: str
    effect: str
    joint: int
    unit: str
    value: float
    stderr: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise InputError(f"MotionEstimate {self.name}: value must be finite")

    @property
    def ci95(self) -> tuple[float, float]:
        return (self.value - Z95 * self.stderr, self.value + Z95 * self.stderr)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "effect": self.effect, "joint": self.joint,
                "unit": self.unit, "value": self.value,
                "stderr": self.stderr if math.isfinite(self.stderr) else None,
                "ci95": list(self.ci95) if math.isfinite(self.stderr) else None}


@dataclass(frozen=True)
class MotionStep:
    """One effect added by the search.

    Attributes:
        effect: its name; joints: the joints it acts on (0: all joints).
        cv_rms: cross-validated RMS over time-segment folds (length unit).
        p_value, bic_delta: against the model before the step.
        withheld: errors on the withheld time segments after the step.
        candidates: the ranking at this step (dicts: effect, joints, cv_rms, p_value, ...).
        ties: candidates within 1 % of the winner's CV RMS.
    """

    effect: str
    joints: tuple[int, ...]
    cv_rms: float
    p_value: float
    bic_delta: float
    withheld: Metrics
    candidates: tuple[dict[str, Any], ...]
    ties: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


@dataclass(frozen=True)
class PhaseError:
    """RMS error (length unit) of the samples in one phase of the motion, before (after
    registration) and after the final model, on all samples and on the withheld ones."""

    phase: str
    n_samples: int
    rms_before: float | None
    rms_after: float | None
    withheld_before: float | None
    withheld_after: float | None

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


@dataclass(frozen=True, eq=False)
class MotionDiagnosis(EffectsFound):
    """Where, which and how far, along a trajectory.

    Attributes:
        model, length_unit: the nominal model's name and unit.
        settings: the options and data sizes.
        nominal: withheld errors after registration only.
        steps: the effects added, in order.
        final: withheld errors with the final model (all fitting samples).
        parameters: final estimates (motion effects only).
        noise_sigma: tracker noise per coordinate (length unit) and ``noise_method``
            ("given" or "second_differences").
        phases: errors per phase of the motion (the "where").
        split: withheld segments and sample counts.
        timing: seconds per stage.
        path_before, path_after: the model's predicted points in the measurement frame,
            before (registration only) and after (final model), shape (S, M, 3).
        warnings: plain-words notes.
        registration: the final model's instrument-from-base rotation (3, 3) and translation
            (3,) (length unit): a base-frame point p is R p + t in the measurement frame.
    """

    model: str
    length_unit: str
    settings: dict[str, Any]
    nominal: Metrics
    steps: tuple[MotionStep, ...]
    final: Metrics
    parameters: tuple[MotionEstimate, ...]
    noise_sigma: float
    noise_method: str
    phases: tuple[PhaseError, ...]
    split: dict[str, Any]
    timing: dict[str, float]
    path_before: F64
    path_after: F64
    warnings: tuple[str, ...] = ()
    registration: tuple[F64, F64] | None = None

    def __post_init__(self) -> None:
        if self.path_before.shape != self.path_after.shape:
            raise InputError("MotionDiagnosis: path_before and path_after shapes differ")
        if self.noise_method not in ("given", "second_differences"):
            raise InputError(f"MotionDiagnosis.noise_method: {self.noise_method!r}")

    @property
    def noise_rms(self) -> float:
        """3-D RMS of pure noise, sqrt(3) sigma."""
        return math.sqrt(3.0) * self.noise_sigma

    @property
    def ratio_to_noise(self) -> float:
        """Final withheld RMS / the noise's 3-D RMS."""
        return self.final.rms / self.noise_rms if self.noise_rms > 0 else math.inf

    @property
    def unexplained(self) -> bool:
        """The final withheld RMS exceeds 1.5x the noise RMS."""
        return self.ratio_to_noise > 1.5

    @property
    def verdict(self) -> str:
        u = self.length_unit
        lines = []
        if not self.steps:
            lines.append("No motion effect explains the gap significantly.")
        for s in self.steps:
            j = "all joints" if s.joints == (0,) else "joints " + ", ".join(map(str, s.joints))
            tie = f" (the data cannot tell it from {', '.join(s.ties)})" if s.ties else ""
            lines.append(f"{s.effect} on {j}: withheld RMS {s.withheld.rms:.4g} {u}{tie}.")
        worst = max((p for p in self.phases if p.rms_before is not None),
                    key=lambda p: p.rms_before or 0.0, default=None)
        if worst is not None:
            lines.append(f"Before correction the gap is largest in the '{worst.phase}' phase "
                         f"(RMS {worst.rms_before:.4g} {u}).")
        lines.append(f"Withheld time segments: RMS {self.nominal.rms:.4g} -> "
                     f"{self.final.rms:.4g} {u}, {self.ratio_to_noise:.2f}x the tracker noise "
                     f"({self.noise_rms:.4g} {u}, {self.noise_method}).")
        if self.unexplained:
            lines.append("A gap remains that no motion effect in the library explains.")
        return " ".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"schema_version": 1, "kind": "motion", "model": self.model,
                "length_unit": self.length_unit, "settings": self.settings,
                "nominal": self.nominal.to_dict(),
                "steps": [s.to_dict() for s in self.steps], "effects": list(self.effects),
                "final": {**self.final.to_dict(), "shrink": self.final.rms / self.nominal.rms
                          if self.nominal.rms > 0 else None,
                          "ratio_to_noise": self.ratio_to_noise,
                          "parameters": [p.to_dict() for p in self.parameters]},
                "noise": {"sigma": self.noise_sigma, "rms": self.noise_rms,
                          "method": self.noise_method},
                "unexplained": self.unexplained, "verdict": self.verdict,
                "where": {"phases": [p.to_dict() for p in self.phases]},
                "split": self.split, "timing": self.timing, "warnings": list(self.warnings)}
