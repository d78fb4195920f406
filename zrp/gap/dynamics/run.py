"""The dynamic gap as a user runs it (``zrp diagnose-dynamics``; notebooks and studies call
the same): diagnose a torque log, score the corrected model on a second log when one is
given, write the corrected model and re-simulate the logged command through it when the arm
can (MuJoCo's :class:`mjcf.arm.Arm` can); the report writes it all
(:func:`zrp.gap.dynamics.report.write_run`).

Everything MuJoCo computes comes through the arm: :class:`~zrp.gap.dynamics.arm.DynamicArm`
for the diagnosis, :class:`ModelWriter` (optional) for the corrected model and the tracking.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis, DynamicsOptions, diagnose_dynamics
from zrp.gap.dynamics.samelog import check_other_arrays
from zrp.gap.dynamics.validation import Validation, validate

__all__ = ["DynamicsRun", "ModelWriter", "TrackingOptions", "run_dynamics"]


@runtime_checkable
class ModelWriter(Protocol):
    """What an arm that can write its corrected model offers (MuJoCo's: MJCF)."""

    def corrected_model(self, diag: DynamicDiagnosis) -> tuple[str, list[str]]:
        """The corrected model's text and what it holds, in words."""
        ...

    def track(self, corrected_xml: str, log: TorqueLog, *, kp: F64 | None = None,
              kv: F64 | None = None, seconds: float | None = None) -> Any:
        """The tracking gap of the model and of the corrected one along the log's command
        (an object with ``before_rad``, ``after_rad``, ``servo``), or None."""
        ...


@dataclass(frozen=True, kw_only=True)
class TrackingOptions:
    """The re-simulation's servo (stiffness kp, damping kv per joint; None: tuned from the
    model) and how much of the log (seconds; None: all)."""

    kp: F64 | None = None
    kv: F64 | None = None
    seconds: float | None = None


@dataclass(frozen=True)
class DynamicsRun:
    """A run's results: the diagnosis, its validation on a second log (or None), the
    corrected model's text (or None when the arm cannot write one) with notes, and the
    tracking gap (or None)."""

    diagnosis: DynamicDiagnosis
    validation: Validation | None = None
    corrected_model: str | None = None
    model_notes: list[str] = field(default_factory=list)
    tracking: Any = None


def run_dynamics(arm: DynamicArm, log: TorqueLog, *, options: DynamicsOptions | None = None,
                 validation_log: TorqueLog | None = None, writer: ModelWriter | None = None,
                 tracking: TrackingOptions | None = None,
                 progress: Callable[[str], None] | None = None) -> DynamicsRun:
    """Diagnose ``log`` (module docstring); ``validation_log`` a second run to score on;
    ``writer`` the arm's corrected-model writer (:class:`mjcf.corrected.CorrectedMJCF`);
    ``progress(stage)`` is called as each stage starts (its name, in words)."""
    stage = progress or (lambda name: None)
    opt = options or DynamicsOptions()
    if validation_log is not None:
        check_other_arrays(log.t, log.q, log.tau, validation_log.t, validation_log.q,
                           validation_log.tau)
    stage("diagnosing")
    diag = diagnose_dynamics(arm, log, opt)
    if validation_log is not None:
        stage("validating on the second log")
    check = None if validation_log is None else validate(arm, diag, validation_log, opt)
    if writer is None:
        return DynamicsRun(diag, check)
    stage("writing the corrected model")
    text, notes = writer.corrected_model(diag)
    tr = tracking or TrackingOptions()
    stage("re-simulating the command")
    track = writer.track(text, log, kp=tr.kp, kv=tr.kv, seconds=tr.seconds)
    return DynamicsRun(diag, check, text, notes, track)
