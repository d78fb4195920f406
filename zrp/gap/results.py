"""What a diagnosis returns: typed, frozen results with their JSON form (``to_dict``).

The results of each search step (:class:`ParameterEstimate`, :class:`Candidate`,
:class:`Step`) live in :mod:`zrp.gap.search.steps` and are re-exported here. The JSON schema is
documented in zrp/gap/README.md; :data:`SCHEMA_VERSION` names it. The plain-words verdict is
prose, so the report words it from the result (:func:`zrp.gap.report.verdict_text`) and adds it
to diagnosis.json (:func:`zrp.gap.report.diagnosis_document`); nothing here refers to the
report.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.analysis.assessment import Assessment
from zrp.gap.analysis.checks import GapWarning as GapWarning
from zrp.gap.analysis.identifiability import EffectIdentifiability as EffectIdentifiability
from zrp.gap.analysis.where import WhereAnalysis
from zrp.gap.data.noise import NoiseFloor
from zrp.gap.finalrecord import FinalModelRecord, final_model_record
from zrp.gap.fit.aliasing import Aliased
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.metrics import Metrics
from zrp.gap.fit.wellposed import HeldDirection
from zrp.gap.model.context import Context
from zrp.gap.search.determination import Determination, determinations
from zrp.gap.search.posefit import FullPoseResult
from zrp.gap.search.steps import Z95 as Z95
from zrp.gap.search.steps import BacklashSwitch as BacklashSwitch
from zrp.gap.search.steps import Candidate as Candidate
from zrp.gap.search.steps import EffectsFound
from zrp.gap.search.steps import ParameterEstimate as ParameterEstimate
from zrp.gap.search.steps import Step as Step
from zrp.gap.search.steps import parameter_estimates as parameter_estimates
from zrp.jsonio import MAX_DIAGNOSIS_BYTES, read_json, version_field

__all__ = [
    "SCHEMA_VERSION",
    "UNEXPLAINED_RATIO",
    "BacklashSwitch",
    "Candidate",
    "Diagnosis",
    "DiagnosisRecord",
    "EffectIdentifiability",
    "GapWarning",
    "ParameterEstimate",
    "Step",
    "StepRecord",
    "Where",
    "load_diagnosis",
    "parameter_estimates",
]

#: 2 (0.5.0): ``final_model_record`` (:mod:`zrp.gap.finalrecord`); ``joint`` null, not 0, for
#: parameters of no joint (registration, kappa): joints count from 1 in every file
SCHEMA_VERSION = 2
#: final withheld RMS above this multiple of the noise-floor RMS counts as unexplained.
UNEXPLAINED_RATIO = 1.5


@dataclass(frozen=True, eq=False)
class Where(Mapping[str, Any]):
    """Where the gap lies: the "where" section of a :class:`Diagnosis`.

    Attributes:
        nominal: the analysis of the residual after registration (fitting poses).
        identifiability: per effect, what these data cannot identify.
        backlash: the flank model of ``backlash`` when that effect was added.
        last_candidates: the candidates of the step at which the search stopped (none was
            added), or None.
        backward_pruned: significance groups dropped in the backward pass.
        after_final_model: the analysis of the residual of the final model (when an effect
            was added).

    Read-only mapping access (``where["projection"]``, ``where.get("backlash_switch")``) gives
    the JSON form (:meth:`to_dict`), for code written against the dictionary this replaces.
    """

    nominal: WhereAnalysis
    identifiability: Mapping[str, EffectIdentifiability] = field(default_factory=dict)
    backlash: BacklashSwitch | None = None
    last_candidates: tuple[Candidate, ...] | None = None
    backward_pruned: tuple[str, ...] = ()
    after_final_model: WhereAnalysis | None = None

    def to_dict(self) -> dict[str, Any]:
        out = self.nominal.to_dict()
        out["identifiability"] = {e: v.to_dict() for e, v in self.identifiability.items()}
        if self.backlash is not None:
            out.update(self.backlash.to_dict())
        if self.last_candidates is not None:
            out["last_candidates"] = [c.to_dict() for c in self.last_candidates]
        if self.backward_pruned:
            out["backward_pruned"] = list(self.backward_pruned)
        if self.after_final_model is not None:
            out["after_final_model"] = self.after_final_model.to_dict()
        return out

    def __getitem__(self, key: str) -> Any:
        return self.to_dict()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.to_dict())

    def __len__(self) -> int:
        return len(self.to_dict())


@dataclass(frozen=True, eq=False)
class Diagnosis(EffectsFound):
    """The result of :func:`~zrp.gap.diagnose` (see zrp/gap/README.md for the JSON form).

    Attributes:
        model_name, length_unit: of the nominal model.
        nominal: withheld errors after registration only.
        nominal_fitting: fitting-set errors after registration only.
        registration: the registration parameters (base frame, tool offsets).
        steps: effects added, in order.
        final: withheld errors of the final model.
        noise_floor: the noise estimate.
        unexplained: True when the final withheld RMS exceeds UNEXPLAINED_RATIO x the noise
            floor RMS; None when there is no noise estimate.
        split: pose ids of the fitting and withheld sets and the CV folds.
        where: the "where" analysis (:class:`Where`).
        aliased: parameters that the data cannot tell apart (reported, never absorbed).
        warnings: messages of the warnings raised during the run.
        nominal_fit, final_fit: the fits (for plots and in-process use).
        withheld_residual_before, withheld_residual_after: shape (3 Rw,).
        context: the data context.
        withheld_poses, fitting_poses: pose indices, shapes (Pw,), (Pf,).
        settings: the options of the run.
        assessment: the geometric baseline, robust intervals, correlations, plausibility,
            the full registration and the evidence on what remains
            (:class:`~zrp.gap.analysis.assessment.Assessment`).
        full_pose: the final model refitted with orientations (:mod:`zrp.gap.search.posefit`).
    """

    model_name: str
    length_unit: str
    nominal: Metrics
    nominal_fitting: Metrics
    registration: tuple[ParameterEstimate, ...]
    steps: tuple[Step, ...]
    final: Metrics
    noise_floor: NoiseFloor
    unexplained: bool | None
    split: dict[str, Any]
    where: Where
    aliased: tuple[Aliased, ...]
    warnings: tuple[str, ...]
    nominal_fit: FitResult
    final_fit: FitResult
    withheld_residual_before: F64
    withheld_residual_after: F64
    context: Context
    fitting_poses: NDArray[np.int64]
    withheld_poses: NDArray[np.int64]
    settings: dict[str, Any] = field(default_factory=dict)
    assessment: Assessment | None = None
    full_pose: FullPoseResult | None = None

    def __post_init__(self) -> None:
        if not all(isinstance(st, Step) for st in self.steps):
            raise InputError("Diagnosis.steps: expected Step objects")
        if self.unexplained is not None and not isinstance(self.unexplained, bool):
            raise InputError(f"Diagnosis.unexplained: expected True, False or None, got "
                             f"{self.unexplained!r}")
        if np.intersect1d(self.fitting_poses, self.withheld_poses).size:
            raise InputError("Diagnosis: fitting and withheld poses overlap")

    @property
    def shrink(self) -> float:
        """Final over nominal withheld RMS (1: no improvement)."""
        return self.final.rms / self.nominal.rms if self.nominal.rms > 0 else 1.0

    @property
    def ratio_to_noise_floor(self) -> float | None:
        """Final withheld RMS over the noise-floor RMS (None without a usable floor)."""
        nf = self.noise_floor.rms
        return None if nf is None or nf == 0 else self.final.rms / nf

    @property
    def where_final(self) -> WhereAnalysis:
        """The analysis of what the final model leaves (the nominal one when nothing was
        added)."""
        final = self.where.after_final_model
        return self.where.nominal if final is None else final

    @property
    def final_parameters(self) -> tuple[ParameterEstimate, ...]:
        """All effect parameters of the final model, estimated jointly (after the backward
        pass), with robust 95 % intervals (:mod:`zrp.gap.fit.uncertainty`). The per-step values
        are each estimated without the effects added later, so these are the ones to use."""
        se = None if self.assessment is None else self.assessment.stderr
        return parameter_estimates(self.final_fit, len(self.registration), stderr=se,
                                   simultaneous=True)

    @property
    def final_joints(self) -> dict[str, tuple[int, ...]]:
        """Effect -> joints (body-vector indices for link_length) in the final model."""
        out: dict[str, set[int]] = {}
        for s in self.final_fit.specs[len(self.registration):]:
            out.setdefault(s.effect, set())
            if s.joint > 0:
                out[s.effect].add(s.joint)
        return {e: tuple(sorted(j)) for e, j in out.items()}

    def parameter(self, name: str) -> ParameterEstimate:
        """The final estimate of one parameter (registration or effect)."""
        for p in self.final_parameters + self.registration:
            if p.name == name:
                return p
        raise InputError(f"no identified parameter {name!r}; identified: "
                         f"{', '.join(p.name for p in self.final_parameters)}")

    @property
    def held_directions(self) -> tuple[HeldDirection, ...]:
        """The parameter combinations of the final model that the data cannot pin, kept at
        their nominal values (:mod:`zrp.gap.fit.wellposed`)."""
        return self.final_fit.held

    @property
    def determination(self) -> dict[str, Determination]:
        """Parameter name -> what the data determine about it (registration and final model:
        held, undetermined with the direction it belongs to, or determined;
        :mod:`zrp.gap.search.determination`)."""
        a = self.assessment
        return determinations(self.final_fit, self.registration + self.final_parameters,
                              gap=self.nominal.rms, unit=self.length_unit,
                              max_tilt_rad=self.context.max_tilt_rad,
                              correlations=None if a is None else a.correlations)

    @property
    def solver_stops(self) -> tuple[str, ...]:
        """Fits that stopped before converging, in words (empty when every fit converged):
        the final model's, the geometric baseline's and any fit whose warning was caught."""
        out = [] if self.final_fit.converged else [f"final model: {self.final_fit.stop_reason}"]
        b = None if self.assessment is None else self.assessment.baseline.fit
        if b is not None and not b.converged:
            out.append(f"geometric calibration: {b.stop_reason}")
        if self.full_pose is not None and not self.full_pose.fit.converged:
            out.append(f"full-pose refit: {self.full_pose.fit.stop_reason}")
        out += [w for w in self.warnings if w.startswith("least squares with")]
        return tuple(dict.fromkeys(out))

    @property
    def outside_domain(self) -> tuple[tuple[str, str], ...]:
        """(effect, why) of the candidates whose fitted values left their physical domains
        (:mod:`zrp.gap.model.domains`) and were taken out or not added."""
        cands = [c for st in self.steps for c in st.candidates]
        cands += list(self.where.last_candidates or ())
        return tuple(dict.fromkeys((c.effect, c.note) for c in cands
                                   if "physical domain" in c.note))

    @cached_property
    def calibration_record(self) -> FinalModelRecord:
        """What a calibration takes from this diagnosis (its full-pose refit when it has one,
        else its final model; :mod:`zrp.gap.finalrecord`), as diagnosis.json stores it."""
        return final_model_record(self)

    def identification(self) -> dict[str, Any]:
        """The well-posedness record of diagnosis.json's ``identification``."""
        f = self.final_fit
        return {"held_directions": [h.to_dict() for h in self.held_directions],
                "solver": {"converged": f.converged, "iterations": f.iterations,
                           "reason": f.stop_reason},
                "stopped_early": list(self.solver_stops),
                "undetermined": [d.to_dict() for d in self.determination.values()
                                 if not d.determined],
                "outside_domain": [{"effect": e, "note": n} for e, n in self.outside_domain],
                "max_tilt_rad": self.context.max_tilt_rad,
                "full_pose": None if self.full_pose is None else {
                    "held_directions": [h.to_dict() for h in self.full_pose.fit.held],
                    "converged": self.full_pose.fit.converged,
                    "reason": self.full_pose.fit.stop_reason,
                    "outside_domain": list(self.full_pose.fit.outside_domain)}}

    def to_dict(self) -> dict[str, Any]:
        """The JSON document (schema in zrp/gap/README.md) without the verdict, which the
        report words and inserts after ``unexplained``
        (:func:`zrp.gap.report.diagnosis_document`)."""
        return {
            "schema_version": SCHEMA_VERSION,
            "model": self.model_name,
            "length_unit": self.length_unit,
            "settings": self.settings,
            "nominal": {**self.nominal.to_dict(), "fitting": self.nominal_fitting.to_dict()},
            "registration": [p.to_dict() for p in self.registration],
            "steps": [s.to_dict() for s in self.steps],
            "effects": list(self.effects),
            "final": {**self.final.to_dict(), "shrink": self.shrink,
                      "effects": [{"effect": e, "joints": list(j)}
                                  for e, j in self.final_joints.items()],
                      "parameters": [p.to_dict() for p in self.final_parameters],
                      "ratio_to_noise_floor": self.ratio_to_noise_floor},
            "noise_floor": self.noise_floor.to_dict(),
            "unexplained": self.unexplained,
            "split": self.split,
            "where": self.where.to_dict(),
            "aliased": [a.to_dict() for a in self.aliased],
            "identification": self.identification(),
            "warnings": list(self.warnings),
            **({} if self.assessment is None else self.assessment.to_dict()),
            "full_pose": None if self.full_pose is None else self.full_pose.to_dict(),
            "final_model_record": self.calibration_record.to_dict(),
        }


@dataclass(frozen=True)
class StepRecord:
    """One step of a stored diagnosis: the effect added, its joints and the candidates ranked
    at that step."""

    effect: str
    joints: tuple[int, ...]
    candidates: tuple[Candidate, ...] = ()


@dataclass(frozen=True)
class DiagnosisRecord(EffectsFound):
    """A diagnosis read back from its JSON document (:func:`load_diagnosis`): the typed,
    read-only part that readers of stored diagnoses (the blind benchmark's scorer) use.

    Attributes:
        steps: the effects added, in order (``effects``, ``top_effect`` as on
            :class:`Diagnosis`).
        nominal_rms, final_rms: withheld RMS after registration and with the final model
            (NaN for a refusal).
        unexplained: as in :class:`Diagnosis`.
        final_parameters: the final model's effect parameters with their intervals.
        error: why the diagnosis refused the data (a document written for a refusal), or None.
    """

    steps: tuple[StepRecord, ...]
    nominal_rms: float
    final_rms: float
    unexplained: bool | None
    final_parameters: tuple[ParameterEstimate, ...] = ()
    error: str | None = None


def _number(x: Any) -> float:
    """A JSON number, null (NaN or an infinity written by :func:`zrp.jsonio.to_jsonable`) as
    NaN."""
    return math.nan if x is None else float(x)


def _candidate(c: Mapping[str, Any]) -> Candidate:
    return Candidate(c["effect"], tuple(int(j) for j in c["joints"]), int(c["n_params"]),
                     _number(c["cv_rms"]), _number(c["bic_delta"]), float(c["p_value"]),
                     bool(c["significant"]), str(c.get("note", "")))


def _parameter(p: Mapping[str, Any]) -> ParameterEstimate:
    ci = p.get("ci95_effect")
    return ParameterEstimate(p["name"], p["effect"], int(p["joint"] or 0), p["unit"],
                             float(p["value"]), float(p["stderr"]),
                             (_number(p["ci95"][0]), _number(p["ci95"][1])),
                             None if ci is None else (_number(ci[0]), _number(ci[1])))


def _step(s: Mapping[str, Any]) -> StepRecord:
    return StepRecord(s["effect"], tuple(int(j) for j in s.get("joints", ())),
                      tuple(_candidate(c) for c in s.get("candidates", ())))


def load_diagnosis(source: str | os.PathLike[str] | Mapping[str, Any]) -> DiagnosisRecord:
    """Read a diagnosis back from its JSON: a diagnosis.json path, or the document itself
    (:meth:`Diagnosis.to_dict`, :func:`zrp.gap.report.diagnosis_document`, or a refusal
    ``{"steps": [], "nominal": {"rms": NaN}, "final": {"rms": NaN}, "unexplained": None,
    "error": ...}``). Keys a reader does not need may be missing (``candidates``,
    ``final.parameters``, ``error``).

    Raises:
        InputError: a step, candidate or parameter the typed results refuse.
        KeyError: the document lacks ``nominal.rms``, ``final.rms`` or a step's ``effect``.
    """
    doc = (source if isinstance(source, Mapping)
           else read_json(source, max_bytes=MAX_DIAGNOSIS_BYTES, what="diagnosis.json"))
    if "schema_version" in doc:  # the in-memory documents and refusals may omit it
        # schema 1 (0.4.0) holds every field read here; schema 2 adds the final model's record
        version_field(doc, "schema_version", (1, SCHEMA_VERSION), src=str(
            "the diagnosis" if isinstance(source, Mapping) else source))
    final = doc["final"]
    return DiagnosisRecord(tuple(_step(s) for s in doc.get("steps", ())),
                           _number(doc["nominal"]["rms"]), _number(final["rms"]),
                           doc.get("unexplained"),
                           tuple(_parameter(p) for p in final.get("parameters", ())),
                           doc.get("error"))
