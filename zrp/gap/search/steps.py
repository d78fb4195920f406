"""What each step of the greedy effect search records: the identified parameters with their
intervals (:class:`ParameterEstimate`), the candidates tried (:class:`Candidate`) and the effect
added (:class:`Step`), with their JSON form (``to_dict``; schema in zrp/gap/README.md).

The whole diagnosis that holds them is :class:`zrp.gap.results.Diagnosis`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.aliasing import Aliased
from zrp.gap.fit.leastsq import Z95 as Z95
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.metrics import Metrics
from zrp.gap.fit.uncertainty import simultaneous_z
from zrp.gap.model.context import EFFECTS
from zrp.jsonio import dict_from_dataclass

__all__ = [
    "BacklashSwitch",
    "Candidate",
    "EffectsFound",
    "ParameterEstimate",
    "Step",
    "parameter_estimates",
]

#: two-sided 95 % quantile of the standard normal distribution.


@dataclass(frozen=True)
class ParameterEstimate:
    """An identified parameter with its 95 % confidence interval (normal approximation) and,
    for the final model, ``ci95_effect``: the simultaneous 95 % interval that holds for all
    parameters of its effect at once (:func:`~zrp.gap.fit.uncertainty.simultaneous_z`)."""

    name: str
    effect: str
    joint: int
    unit: str
    value: float
    stderr: float
    ci95: tuple[float, float]
    ci95_effect: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise InputError(f"ParameterEstimate {self.name}: value {self.value} is not finite")
        if not (self.stderr >= 0):
            raise InputError(f"ParameterEstimate {self.name}: stderr {self.stderr} < 0")

    def to_dict(self) -> dict[str, Any]:
        """The JSON form; ``joint`` 1-based, null for a parameter of no joint (registration,
        kappa)."""
        d = dict_from_dataclass(self, exclude=() if self.ci95_effect else ("ci95_effect",))
        d["joint"] = self.joint or None
        return d


def parameter_estimates(result: FitResult, first: int, last: int | None = None,
                        stderr: F64 | None = None, simultaneous: bool = False
                        ) -> tuple[ParameterEstimate, ...]:
    """The parameters ``first`` .. ``last`` (default: all after ``first``) of a fit, with
    their 95 % intervals (from ``stderr``, shape (p,), default the normal-theory ones) and,
    with ``simultaneous``, the per-effect simultaneous ones over these parameters."""
    se = result.stderr if stderr is None else stderr
    idx = range(first, len(result.specs) if last is None else last)
    k_of: dict[str, int] = {}
    for i in idx:
        k_of[result.specs[i].effect] = k_of.get(result.specs[i].effect, 0) + 1
    out = []
    for i in idx:
        s = result.specs[i]
        v = float(result.theta[i])
        h = Z95 * float(se[i])
        joint = None
        if simultaneous:
            hj = simultaneous_z(k_of[s.effect]) * float(se[i])
            joint = (v - hj, v + hj)
        out.append(ParameterEstimate(s.name, s.effect, s.joint, s.unit, v, float(se[i]),
                                     (v - h, v + h), joint))
    return tuple(out)


def _nan_to_none(x: float) -> float | None:
    return None if math.isnan(x) else x


@dataclass(frozen=True)
class Candidate:
    """One effect tried at one step of the greedy search.

    Attributes:
        effect: the effect.
        joints: joints (or body vectors for ``link_length``) whose parameters were significant.
        n_params: parameters kept after the significance pruning.
        cv_rms: cross-validated 3-D RMS on the fitting set (length unit); NaN if not fitted.
        bic_delta: BIC change against the current model (negative is better).
        p_value: F test of the improvement against the current model.
        significant: it passed all the tests for being added.
        note: why it was not tried or not significant.
    """

    effect: str
    joints: tuple[int, ...]
    n_params: int
    cv_rms: float
    bic_delta: float
    p_value: float
    significant: bool
    note: str = ""

    def __post_init__(self) -> None:
        if self.effect not in EFFECTS:
            raise InputError(f"Candidate.effect: {self.effect!r} not in {EFFECTS}")
        if not 0.0 <= self.p_value <= 1.0:
            raise InputError(f"Candidate {self.effect}: p_value {self.p_value} not in [0, 1]")

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self, nan_to_none=("cv_rms", "bic_delta"))


@dataclass(frozen=True)
class Step:
    """One effect added to the model, with what it achieved on the withheld poses."""

    effect: str
    joints: tuple[int, ...]
    parameters: tuple[ParameterEstimate, ...]
    withheld: Metrics
    fitting: Metrics
    cv_rms: float
    p_value: float
    bic_delta: float
    candidates: tuple[Candidate, ...]
    aliased: tuple[Aliased, ...]
    geometric_overlap: float = math.nan
    ties: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.effect not in EFFECTS:
            raise InputError(f"Step.effect: {self.effect!r} not in {EFFECTS}")
        bad = [t for t in self.ties if t not in EFFECTS]
        if bad:
            raise InputError(f"Step.ties: {bad} not in {EFFECTS}")

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.effect, "joints": list(self.joints), "ties": list(self.ties),
                "geometric_overlap": _nan_to_none(self.geometric_overlap),
                "parameters": [p.to_dict() for p in self.parameters],
                "rms": self.withheld.rms, "p95": self.withheld.p95, "max": self.withheld.max,
                **dict_from_dataclass(self, exclude=("effect", "joints", "parameters",
                                                     "geometric_overlap", "ties"))}


class EffectsFound:
    """The effects a diagnosis found, read from its ``steps`` (each has an ``effect``): one
    home for :class:`~zrp.gap.results.Diagnosis` and
    :class:`~zrp.gap.motion.results.MotionDiagnosis` (a mixin without fields)."""

    steps: tuple[Any, ...]

    @property
    def effects(self) -> tuple[str, ...]:
        """Effects found, in order ("none" alone when nothing helped)."""
        return tuple(s.effect for s in self.steps) or ("none",)

    @property
    def top_effect(self) -> str:
        """The first effect found, or "none"."""
        return self.effects[0]


@dataclass(frozen=True)
class BacklashSwitch:
    """Where a joint with play rests (the ``backlash`` effect as added to the model).

    Attributes:
        switch: per joint, the gravity torque above which it rests on the loaded flank (None:
            always against its approach direction).
        band: per joint, the range of plausible switching torques (None where modelled by the
            approach direction only).
        payload_kg: the unknown payload at the tool profiled with MJCF torques, kg.
        lead: per joint, whether the approach leaves the load on the leading flank of its play
            (its inertia carries it over as the motor stops) rather than lagging behind.
        weights: per joint, the plausible switching torques and their weights the fit used
            (:attr:`zrp.gap.model.context.Context.backlash_switch_weights`), or None.
    """

    switch: tuple[float | None, ...]
    band: tuple[list[float] | None, ...]
    payload_kg: float
    lead: tuple[bool, ...] = ()
    weights: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self, exclude=("weights",),
                                   rename={"switch": "backlash_switch",
                                                 "band": "backlash_switch_band",
                                                 "payload_kg": "backlash_payload_kg",
                                                 "lead": "backlash_lead"})
