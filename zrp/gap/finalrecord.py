"""The final model of a diagnosis in the numbers a calibration needs (:class:`FinalModelRecord`),
stored in diagnosis.json as ``final_model_record`` so that ``zrp calibrate --diagnosis`` builds
the calibrated robot without repeating the search.

What it holds (the corrected model of zrp/gap/README.md evaluated once): the identified joint
axes and body vectors (n, 3), (n + 1, 3) before the revolute offsets are folded in, the tool
offsets (M, 3), the instrument-from-base transform, the joint-space parameters (offsets, the
joint map, kappa) with their standard errors, the backlash flank model, the lumped masses of
the gravity side, the parameters the data did not determine, the ones taken out as
non-physical and, after a full-pose refit, the probe rotation and noise weights. The
calibration writes what this record says (:meth:`zrp.calibration.CalibratedRobot.from_record`)
whether it was just computed or read back, so a calibration from a stored diagnosis is the same
file as a fresh one: every number passes the JSON form (floats written in full, read back
exactly) in both cases.

It records the SHA-256 of the nominal model (its TOML text) and of the measurements
diagnosed (:func:`zrp.gap.data.digest.measurements_sha256`): a record is refused for other
ones (:meth:`FinalModelRecord.check`). It is bound to its own content too (record version 2,
issue 41): ``content_sha256``, written last and checked first, and every value in its domain
when it is made and when it is read, by one checker (:mod:`zrp.gap.recordcheck`).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.digest import measurements_sha256
from zrp.gap.data.measurements import Measurements
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.model.context import Context
from zrp.gap.model.problem import Problem
from zrp.gap.recordcheck import (
    HASH_KEY,
    MAX_HARMONIC,
    RecordDomainError,
    TamperedRecordError,
    check_content,
    content_sha256,
    joint_index,
    record_problems,
    switch_weights,
    whole,
)
from zrp.gap.recordcheck import number as _num
from zrp.gap.search.determination import fit_determinations
from zrp.jsonio import to_jsonable
from zrp.model.files import dumps_model
from zrp.model.manipulator import Manipulator


class Diagnosis(Protocol):
    """What :func:`final_model_record` reads of a :class:`zrp.gap.Diagnosis` (named here,
    not imported: the diagnosis's results sit above this module and store its record)."""

    context: Context
    settings: dict[str, Any]
    fitting_poses: Any
    full_pose: Any
    nominal_fit: FitResult
    final_fit: FitResult
    nominal: Any
    final: Any
    where: Any
    determination: dict[str, Any]
    length_unit: str
    outside_domain: tuple[tuple[str, str], ...]

__all__ = ["RECORD_VERSION", "FinalModelRecord", "ProbeRecord", "RecordDomainError",
           "StaleDiagnosisError", "TamperedRecordError", "final_model_record",
           "full_pose_fit_result", "model_sha256", "switch_weights"]

#: version of the ``final_model_record`` entry (diagnosis.json schema_version 2 on; 2: its
#: ``content_sha256``, issue 41)
RECORD_VERSION = 2
#: the joint-space parameter kinds a calibration keeps (the rest are in the geometry)
_JOINT_KINDS = ("dq", "thermal")


class StaleDiagnosisError(InputError):
    """A stored diagnosis cannot be reused: written before diagnosis.json held its final
    model's record (re-run ``zrp diagnose``), or of other measurements or another model."""


def model_sha256(model: Manipulator) -> str:
    """SHA-256 of the model's TOML text (:func:`zrp.model.files.dumps_model`)."""
    return hashlib.sha256(dumps_model(model).encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class JointParameter:
    """A joint-space parameter of the final model (offset, joint-map term or kappa)."""

    name: str
    effect: str
    kind: str
    joint: int
    unit: str
    value: float
    stderr: float


@dataclass(frozen=True)
class ProbeRecord:
    """The probe frame and noise weights of a full-pose refit (the attributes
    :func:`zrp.calibration.storage.full_pose_document` reads from a
    :class:`~zrp.gap.fit.fullpose.FullPoseFit`)."""

    probe_rotation: F64
    sigma_orientation: float
    sigma_orientation_given: bool
    sigma_position: float
    orientation_rms: float
    orientation: bool = True


@dataclass(frozen=True, eq=False)
class FinalModelRecord:
    """The final model of a diagnosis as a calibration takes it (module doc). Arrays in the
    model's length unit and rad; ``joint`` of a parameter is 1-based."""

    model_sha256: str
    measurements_sha256: str
    source: str
    axes: F64
    bodies: F64
    tool_labels: tuple[str, ...]
    tool_offsets: F64
    base_rotation: F64
    base_translation: F64
    parameters: tuple[JointParameter, ...]
    t_ref_degC: float
    gravity_dir: tuple[float, float, float]
    harmonics: tuple[int, ...]
    frame: str
    compliance_model: str
    withheld_rms: float
    backlash_switch: tuple[float | None, ...] | None = None
    payload_kg: float = 0.0
    backlash_lead: tuple[bool, ...] | None = None
    backlash_switch_weights: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] | None = None
    gravity_side_weights: F64 | None = None
    undetermined: tuple[str, ...] = ()
    taken_out: tuple[str, ...] = ()
    probe: ProbeRecord | None = None

    def __post_init__(self) -> None:
        bad = record_problems(self)
        if bad:
            raise RecordDomainError(f"final_model_record: {len(bad)} value(s) outside their "
                                    "domain, refused: " + "; ".join(bad))

    def to_dict(self) -> dict[str, Any]:
        """The record as diagnosis.json stores it, its ``content_sha256`` last."""
        doc = self._content()
        return {**doc, HASH_KEY: content_sha256(doc)}

    def _content(self) -> dict[str, Any]:
        p = self.probe
        return to_jsonable({
            "version": RECORD_VERSION, "model_sha256": self.model_sha256,
            "measurements_sha256": self.measurements_sha256, "source": self.source,
            "axes": self.axes, "bodies": self.bodies,
            "tool_points": dict(zip(self.tool_labels, np.asarray(self.tool_offsets).tolist(),
                                    strict=True)),
            "base_rotation": self.base_rotation, "base_translation": self.base_translation,
            "parameters": [{**vars(q), "joint": q.joint or None} for q in self.parameters],
            "t_ref_degC": self.t_ref_degC, "gravity_dir": self.gravity_dir,
            "harmonics": self.harmonics, "frame": self.frame,
            "compliance_model": self.compliance_model, "withheld_rms": self.withheld_rms,
            "backlash": {"switch": self.backlash_switch, "payload_kg": self.payload_kg,
                         "lead": self.backlash_lead,
                         "switch_weights": self.backlash_switch_weights},
            "gravity_side_weights": self.gravity_side_weights,
            "undetermined": self.undetermined, "taken_out_non_physical": self.taken_out,
            "probe": None if p is None else {
                "probe_rotation": p.probe_rotation, "sigma_orientation_rad": p.sigma_orientation,
                "sigma_orientation_given": p.sigma_orientation_given,
                "sigma_position": p.sigma_position, "orientation_rms_rad": p.orientation_rms}})

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], src: str = "final_model_record"
                  ) -> FinalModelRecord:
        """Read a record back (:meth:`to_dict`).

        Raises:
            StaleDiagnosisError: another record version (1: written by 0.5.0 without its
                content hash).
            TamperedRecordError: its content is not the one its ``content_sha256`` names.
            RecordDomainError: a value outside its domain (naming ``src`` and the field).
            InputError: a missing or malformed key (naming ``src``).
        """
        version = d.get("version") if isinstance(d, Mapping) else None
        if type(version) is not int or version != RECORD_VERSION:
            raise StaleDiagnosisError(
                f"{src}: final_model_record version {str(version)[:20]!r}, expected "
                f"{RECORD_VERSION}" + (" (version 1, 0.5.0, does not bind its values: no "
                                       "content_sha256)" if version == 1 and type(version)
                                       is int else "")
                + "; re-run zrp diagnose with this version")
        check_content(d, src)
        try:
            return _from_dict(cls, d)
        except RecordDomainError as exc:
            raise RecordDomainError(f"{src}: {str(exc).removeprefix('final_model_record: ')}"
                                    ) from None
        except (KeyError, TypeError, ValueError, IndexError, OverflowError,
                AttributeError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"{src}: malformed final_model_record ({type(exc).__name__}: "
                             f"{exc})") from None

    def check(self, model: Manipulator, meas: Measurements | None, src: str) -> None:
        """Refuse the record for another nominal model or other measurements (None: the
        diagnosis's own, not checked).

        Raises:
            StaleDiagnosisError: naming which and both hashes.
            RecordDomainError: a value outside its domain on ``model`` (its joints, its
                reach; :func:`zrp.gap.recordcheck.record_problems`).
        """
        pairs = [("model", self.model_sha256, model_sha256(model), f"the model {model.name!r}")]
        if meas is not None:
            pairs.insert(0, ("measurements", self.measurements_sha256, measurements_sha256(meas),
                             f"{meas.source} as read (rows, joint values, positions, frame, "
                             "units)"))
        for what, mine, theirs, hint in pairs:
            if mine != theirs:
                raise StaleDiagnosisError(
                    f"{src}: this diagnosis was made from other {what} (SHA-256 {mine[:12]}... "
                    f"recorded, {theirs[:12]}... for {hint}); diagnose these {what} or pass "
                    "the ones the diagnosis used")
        self.check_domains(model, src)

    def check_domains(self, model: Manipulator, src: str = "final_model_record") -> None:
        """Refuse the record when a value is outside its domain on the nominal ``model``.

        Raises:
            RecordDomainError: naming ``src`` and every such value.
        """
        bad = record_problems(self, model)
        if bad:
            raise RecordDomainError(f"{src}: {len(bad)} value(s) outside their domain on "
                                    f"the model {model.name!r}, refused: " + "; ".join(bad))


def _from_dict(cls: type[FinalModelRecord], d: Mapping[str, Any]) -> FinalModelRecord:
    tools = d["tool_points"]
    arr = (lambda k: np.array(d[k], dtype=float))  # noqa: E731
    return cls(
        str(d["model_sha256"]), str(d["measurements_sha256"]), str(d["source"]), arr("axes"),
        arr("bodies"), tuple(str(k) for k in tools),
        np.array([tools[k] for k in tools], dtype=float).reshape(-1, 3),
        arr("base_rotation"), arr("base_translation"),
        tuple(JointParameter(str(q["name"]), str(q["effect"]), str(q["kind"]),
                             joint_index(q["joint"], f"parameters[{i}].joint"), str(q["unit"]),
                             _num(q["value"], where=f"parameters[{i}].value"),
                             _num(q["stderr"])) for i, q in enumerate(d["parameters"])),
        _num(d["t_ref_degC"], where="t_ref_degC"),
        tuple(_num(v, where="gravity_dir") for v in d["gravity_dir"]),  # type: ignore[arg-type]
        tuple(whole(h, "harmonics", 1, MAX_HARMONIC) for h in d["harmonics"]),
        str(d["frame"]), str(d["compliance_model"]),
        _num(d["withheld_rms"]), **_backlash_from_dict(d["backlash"]),
        gravity_side_weights=(None if d["gravity_side_weights"] is None
                              else arr("gravity_side_weights")),
        undetermined=tuple(str(u) for u in d["undetermined"]),
        taken_out=tuple(str(u) for u in d["taken_out_non_physical"]),
        probe=_probe_from_dict(d["probe"]))


def _backlash_from_dict(bl: Mapping[str, Any]) -> dict[str, Any]:
    lead = bl["lead"]
    if lead is not None and not all(isinstance(v, bool) for v in lead):
        raise RecordDomainError("backlash.lead: expected null or true/false per joint")
    return {"backlash_switch": None if bl["switch"] is None else tuple(
                None if v is None else _num(v, where="backlash.switch") for v in bl["switch"]),
            "payload_kg": _num(bl["payload_kg"], where="backlash.payload_kg"),
            "backlash_lead": None if lead is None else tuple(lead),
            "backlash_switch_weights": switch_weights(bl["switch_weights"])}


def _probe_from_dict(p: Mapping[str, Any] | None) -> ProbeRecord | None:
    if p is None:
        return None
    return ProbeRecord(np.array(p["probe_rotation"], dtype=float),
                       _num(p["sigma_orientation_rad"]), bool(p["sigma_orientation_given"]),
                       _num(p["sigma_position"]), _num(p["orientation_rms_rad"]))


def full_pose_fit_result(diag: Diagnosis) -> FitResult | None:
    """The diagnosis's full-pose refit of its final model as a :class:`FitResult` (its
    parameters with the full-pose values and standard errors, the position block's residual
    and Jacobian), or None without one."""
    if diag.full_pose is None:
        return None
    fp = diag.full_pose.fit
    return FitResult(tuple(fp.specs), fp.theta, np.diag(fp.stderr ** 2), fp.position.residual,
                     fp.position.jac, fp.position.base_rotation,
                     np.asarray(diag.fitting_poses), True)


def _side_weights(ctx: Context) -> F64 | None:
    """The lumped masses behind the diagnosis's ``gravity_side`` torques, shape (n, J): per
    joint, the least-squares combination of the moment-arm columns (exact: the diagnosis built
    them as such a combination), or None with MJCF torques or without a gravity side."""
    if ctx.gravity_torque is not None or ctx.gravity_side is None:
        return None
    _, h = ctx.moment_arms()
    w = np.zeros((ctx.n, h.shape[2]))
    for k in range(ctx.n):
        w[k] = np.linalg.lstsq(h[:, k, :], ctx.gravity_side[:, k], rcond=None)[0]
    return w


def _undetermined(diag: Diagnosis, fit: FitResult) -> tuple[str, ...]:
    """``name: what the data say`` of the parameters of ``fit`` the data did not determine
    (the diagnosis's robust story for its final fit; the fit's own intervals otherwise)."""
    det = (diag.determination if fit is diag.final_fit else fit_determinations(
        fit, gap=diag.nominal.rms, unit=diag.length_unit,
        max_tilt_rad=diag.context.max_tilt_rad))
    return tuple(f"{d.name}: {d.describe()}" for d in det.values() if not d.determined)


def _taken_out(diag: Diagnosis) -> tuple[str, ...]:
    """The effects' values the search or the full-pose refit took out as non-physical."""
    out = [f"{e}: {n}" for e, n in diag.outside_domain]
    b = None if diag.assessment is None else diag.assessment.baseline
    if b is not None and b.combined_fit is not None and diag.final_fit is b.combined_fit:
        out += [f"final model (geometry + non-geometric effects): {n}"
                for n in b.combined_outside]
    if diag.full_pose is not None:
        out += [f"full-pose refit: {n}" for n in diag.full_pose.fit.outside_domain]
    return tuple(dict.fromkeys(out))


def final_model_record(diag: Diagnosis, *, registration_only: bool = False,
                       fit: FitResult | None = None) -> FinalModelRecord:
    """The record of what a calibration takes from ``diag``: its full-pose refit when it has
    one, else its final model; with ``registration_only``, the nominal model with the
    registration alone; with ``fit``, another estimate of the final model's parameters."""
    fit, probe, source = _chosen_fit(diag, registration_only, fit)
    ctx = diag.context
    prob = Problem(ctx, fit.specs, diag.fitting_poses[:1], fit.base_rotation)
    u, _, bodies = prob.geometry(fit.theta)
    rb, tb = prob.base(fit.theta)
    params = tuple(JointParameter(s.name, s.effect, s.kind, s.joint, s.unit, float(v),
                                  float(se))
                   for s, v, se in zip(fit.specs, fit.theta, fit.stderr, strict=True)
                   if s.kind in _JOINT_KINDS)
    rec = FinalModelRecord(
        model_sha256(ctx.model),
        diag.settings.get("measurements_sha256") or measurements_sha256(ctx.meas), source,
        np.asarray(u, dtype=float), np.asarray(bodies, dtype=float),
        tuple(ctx.meas.point_labels), np.asarray(prob.tool_offsets(fit.theta), dtype=float),
        np.asarray(rb, dtype=float), np.asarray(tb, dtype=float), params,
        float(ctx.t_ref_degC), tuple(float(g) for g in ctx.gravity_dir),  # type: ignore[arg-type]
        tuple(int(h) for h in ctx.harmonics), ctx.meas.frame,
        "mjcf" if ctx.gravity_torque is not None else "lumped_masses",
        float(diag.nominal.rms if registration_only else diag.final.rms),
        **_backlash_fields(None if registration_only else diag.where.backlash),
        gravity_side_weights=_side_weights(ctx), undetermined=_undetermined(diag, fit),
        taken_out=() if registration_only else _taken_out(diag), probe=probe)
    rec.check_domains(ctx.model, "the diagnosis's final-model record")  # the reader's checks
    return rec


def _chosen_fit(diag: Diagnosis, registration_only: bool, fit: FitResult | None
                ) -> tuple[FitResult, ProbeRecord | None, str]:
    """The fit a record is made of, the probe of a full-pose refit, and which it is."""
    if fit is not None:
        return fit, None, "registration" if registration_only else "final_fit"
    if registration_only:
        return diag.nominal_fit, None, "registration"
    if diag.full_pose is None:
        return diag.final_fit, None, "final_fit"
    fp = diag.full_pose.fit
    probe = None if not fp.orientation else ProbeRecord(
        np.asarray(fp.probe_rotation, dtype=float), float(fp.sigma_orientation),
        bool(fp.sigma_orientation_given), float(fp.sigma_position), float(fp.orientation_rms))
    chosen = full_pose_fit_result(diag)
    assert chosen is not None  # a full-pose refit exists
    return chosen, probe, "full_pose"


def _backlash_fields(bl: Any) -> dict[str, Any]:
    """The backlash flank model's fields of a record (none without backlash)."""
    if bl is None:
        return {}
    return {"backlash_switch": tuple(None if v is None else float(v) for v in bl.switch),
            "payload_kg": float(bl.payload_kg),
            "backlash_lead": tuple(bool(v) for v in bl.lead) if bl.lead else None,
            "backlash_switch_weights": switch_weights(bl.weights)}
