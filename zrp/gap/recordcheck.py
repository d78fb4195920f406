"""The final-model record's own values, each in its domain, and its content hash (issue 41).

A calibration is built from diagnosis.json's ``final_model_record``
(:mod:`zrp.gap.finalrecord`), and the calibration is what a robot plays. Its SHA-256s of the
model and the measurements bind it to its inputs; this module binds it to its content:

* :func:`content_sha256`: the SHA-256 of the record's canonical JSON (sorted keys, no spaces,
  its ``content_sha256`` left out), written last into the record and checked first when it is
  read (:func:`check_content`): an edited record is refused, naming what to do. (The hash is
  not a signature: whoever recomputes it gets past it, and meets the domains below.)
* :func:`record_problems`: every value in its domain, the same checks when the record is
  written (:func:`zrp.gap.finalrecord.final_model_record`) and when it is read
  (:meth:`~zrp.gap.finalrecord.FinalModelRecord.from_dict`): one checker. Without the model:
  shapes (n joints from ``axes``, 1..:data:`MAX_JOINTS`), finite numbers, unit axes and
  gravity direction, proper rotations (orthonormal to :data:`ROTATION_TOL`, determinant +1),
  known kinds, effects, sources, frames and compliance models, each joint parameter named
  ``q{joint}.`` on a joint 1..n (kappa on none), distinct harmonics 1..:data:`MAX_HARMONIC`,
  bounded counts, a payload 0..:data:`MAX_PAYLOAD_KG`, t_ref in :data:`TEMP_RANGE_DEGC`.
  With the nominal model (:meth:`~zrp.gap.finalrecord.FinalModelRecord.check`, the
  calibration's :meth:`~zrp.calibration.CalibratedRobot.from_record`): its number of joints, a
  revolute joint offset of at most pi, a prismatic one of at most the arm's reach, each body
  vector within :data:`BODY_SHARE` of the reach of its nominal, the base translation within
  :data:`BASE_REACH_FACTOR` times the reach of the instrument, each tool point within
  :data:`TOOL_REACH_FACTOR` times the reach of the end effector (the reach: the sum of the
  nominal body lengths; the same bounds as compensation.json's, :mod:`zrp.calibration.
  filecheck`).

:func:`whole` and :func:`joint_index` are the strict readers of the record's integers: a JSON
integer, not a float, a string or a boolean (``1e999`` is infinity, refused by name, not an
``OverflowError``).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from zrp.errors import InputError
from zrp.model.manipulator import Manipulator

#: a :class:`zrp.gap.finalrecord.FinalModelRecord` (named, not imported: it stands above)
FinalModelRecord = Any

__all__ = ["BASE_REACH_FACTOR", "BODY_SHARE", "MAX_HARMONIC", "MAX_JOINTS", "MAX_PAYLOAD_KG",
           "ROTATION_TOL", "TEMP_RANGE_DEGC", "TOOL_REACH_FACTOR", "RecordDomainError",
           "TamperedRecordError", "check_content", "content_sha256", "joint_index",
           "number", "record_problems", "switch_weights", "whole"]

MAX_JOINTS = 64
MAX_TOOL_POINTS = 1000
MAX_PARAMETERS = 10_000
MAX_SWITCHES = 10_000
MAX_NOTES = 10_000
MAX_HARMONIC = 100
MAX_PAYLOAD_KG = 1.0e4
TEMP_RANGE_DEGC = (-273.15, 1000.0)
ROTATION_TOL = 1e-6
BASE_REACH_FACTOR = 100.0
TOOL_REACH_FACTOR = 2.0
#: a body vector may differ from its nominal by at most this share of the arm's reach
BODY_SHARE = 0.25
HASH_KEY = "content_sha256"
_SOURCES = ("final_fit", "registration", "full_pose")
_JOINT_EFFECTS = ("joint_offset", "encoder_scale", "cyclic_error", "backlash",
                  "joint_compliance")
_CYCLIC = re.compile(r"(sin|cos)([0-9]+)")


class RecordDomainError(InputError):
    """A value of the final-model record outside its domain (naming the field)."""


class TamperedRecordError(InputError):
    """The final-model record's content is not the one its ``content_sha256`` names."""


def content_sha256(doc: Mapping[str, Any]) -> str:
    """SHA-256 of the record's canonical JSON (sorted keys, no spaces), ``content_sha256``
    left out."""
    body = {k: v for k, v in doc.items() if k != HASH_KEY}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":"))
                          .encode("utf-8")).hexdigest()


def check_content(doc: Mapping[str, Any], src: str) -> None:
    """Refuse a record whose content is not the one its ``content_sha256`` names.

    Raises:
        TamperedRecordError: naming ``src`` and what to do.
    """
    named = doc.get(HASH_KEY)
    try:
        actual = content_sha256(doc)
    except (TypeError, ValueError) as exc:
        raise TamperedRecordError(f"{src}: cannot hash the record ({exc})") from None
    if named != actual:
        raise TamperedRecordError(
            f"{src}: {HASH_KEY} {str(named)[:16]!r}... is not the SHA-256 of its content "
            f"({actual[:16]}...): the record was changed after zrp diagnose wrote it; "
            "refused. Use diagnosis.json as written, or re-run zrp diagnose on the data")


def whole(v: object, where: str, lo: int = 0, hi: int = 2**31) -> int:
    """``v`` when it is a JSON integer in [lo, hi].

    Raises:
        RecordDomainError: naming ``where``.
    """
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise RecordDomainError(f"{where}: {_short(v)}; expected a whole number in "
                                f"{lo}..{hi}")
    return v


def joint_index(v: object, where: str) -> int:
    """A parameter's joint: a JSON integer 1..:data:`MAX_JOINTS`, or null (none: 0)."""
    return 0 if v is None else whole(v, where, 1, MAX_JOINTS)


def number(x: Any, missing: float = math.nan, where: str = "a value") -> float:
    """``x`` as a float when it is a JSON number (None: ``missing``).

    Raises:
        RecordDomainError: a string, a boolean or anything else, naming ``where``.
    """
    if x is None:
        return missing
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise RecordDomainError(f"{where}: {str(x)[:40]!r}; expected a number")
    return float(x)


def switch_weights(value: Any) -> tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] | None:
    """Per joint, (switching torques, their weights) as tuples of floats (a null torque, as
    JSON writes infinity: infinity), or None."""
    if value is None:
        return None
    return tuple((tuple(math.inf if t is None else float(t) for t in thr),
                  tuple(float(w) for w in wts))
                 for thr, wts in value)


def _short(v: object) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _finite(a: Any) -> bool:
    return bool(np.all(np.isfinite(np.asarray(a, dtype=float))))


def _rotation(name: str, r: Any) -> list[str]:
    r = np.asarray(r, dtype=float)
    if r.shape != (3, 3) or not _finite(r):
        return [f"{name}: expected a 3x3 rotation of finite numbers, got shape {r.shape}"]
    err = float(np.max(np.abs(r @ r.T - np.eye(3))))
    if err > ROTATION_TOL:
        return [f"{name}: not orthonormal (|R R^T - I| = {err:.3g} > {ROTATION_TOL:g})"]
    if np.linalg.det(r) < 0:
        return [f"{name}: a reflection (determinant -1), not a rotation"]
    return []


def _in(name: str, v: float, lo: float, hi: float, unknown: bool = False) -> list[str]:
    if unknown and math.isnan(v):
        return []
    return [] if lo <= v <= hi else [f"{name}: {v!r}; expected a finite value in "
                                     f"[{lo:g}, {hi:g}]"]


def _arrays(rec: FinalModelRecord) -> list[str]:
    n = len(rec.axes) if np.ndim(rec.axes) == 2 else -1
    out = [] if 1 <= n <= MAX_JOINTS else [f"axes: shape {np.shape(rec.axes)}; expected (n, 3)"
                                           f" with n 1..{MAX_JOINTS}"]
    m = len(rec.tool_labels)
    for name, a, shape in (("axes", rec.axes, (n, 3)), ("bodies", rec.bodies, (n + 1, 3)),
                           ("tool_points", rec.tool_offsets, (m, 3)),
                           ("base_translation", rec.base_translation, (3,))):
        if np.shape(a) != shape or not _finite(a):
            out.append(f"{name}: shape {np.shape(a)}; expected {shape} finite numbers")
    if not out and not np.allclose(np.linalg.norm(rec.axes, axis=1), 1.0, atol=1e-6):
        out.append("axes: expected unit vectors")
    if m > MAX_TOOL_POINTS or len(set(rec.tool_labels)) != m:
        out.append(f"tool_points: {m} labels; expected at most {MAX_TOOL_POINTS}, distinct")
    return out + _rotation("base_rotation", rec.base_rotation)


def _parameter(q: Any, n: int, harmonics: tuple[int, ...]) -> str | None:
    """Why the joint parameter ``q`` is outside its domain, or None."""
    if not math.isfinite(q.value):
        return f"value {q.value!r}; expected a finite number"
    if q.kind == "thermal":
        return None if q.effect == "thermal_expansion" and q.joint == 0 else (
            "kind thermal: expected effect thermal_expansion on no joint")
    if q.kind != "dq":
        return f"kind {q.kind!r}; expected dq or thermal"
    if q.effect not in _JOINT_EFFECTS:
        return f"effect {q.effect!r}; expected one of {', '.join(_JOINT_EFFECTS)}"
    if not 1 <= q.joint <= n:
        return f"joint {q.joint}; expected 1..{n}"
    head, _, what = q.name.partition(".")
    if head != f"q{q.joint}" or not what:
        return f"name {q.name!r} is not joint {q.joint}'s (q{q.joint}.<term>)"
    cyc = _CYCLIC.fullmatch(what)
    if q.effect == "cyclic_error" and (cyc is None or int(cyc.group(2)) not in harmonics):
        return f"{what!r} is not a harmonic of {list(harmonics)} (sin<h> or cos<h>)"
    return None


def _parameters(rec: FinalModelRecord, n: int) -> list[str]:
    if len(rec.parameters) > MAX_PARAMETERS:
        return [f"parameters: {len(rec.parameters)}; expected at most {MAX_PARAMETERS}"]
    out = []
    for i, q in enumerate(rec.parameters):
        why = _parameter(q, n, rec.harmonics)
        if why:
            out.append(f"parameters[{i}] ({_short(q.name)}): {why}")
    names = [q.name for q in rec.parameters]
    if len(set(names)) != len(names):
        out.append("parameters: a name given twice")
    return out


def _scalars(rec: FinalModelRecord) -> list[str]:
    out = []
    for name, v, allowed in (("source", rec.source, _SOURCES),
                             ("frame", rec.frame, ("instrument", "base")),
                             ("compliance_model", rec.compliance_model,
                              ("mjcf", "lumped_masses"))):
        if v not in allowed:
            out.append(f"{name}: {_short(v)}; expected one of {', '.join(allowed)}")
    for name, v in (("model_sha256", rec.model_sha256),
                    ("measurements_sha256", rec.measurements_sha256)):
        if re.fullmatch(r"[0-9a-f]{64}", v) is None:
            out.append(f"{name}: {_short(v)}; expected 64 hexadecimal digits")
    h = rec.harmonics
    if not h or len(set(h)) != len(h) or not all(1 <= v <= MAX_HARMONIC for v in h):
        out.append(f"harmonics: {list(h)[:8]!r}; expected distinct whole numbers "
                   f"1..{MAX_HARMONIC}")
    g = np.asarray(rec.gravity_dir, dtype=float)
    if g.shape != (3,) or not abs(float(np.linalg.norm(g)) - 1.0) <= 1e-6:
        out.append(f"gravity_dir: {_short(rec.gravity_dir)}; expected a unit vector of 3")
    out += _in("t_ref_degC", rec.t_ref_degC, *TEMP_RANGE_DEGC)
    out += _in("withheld_rms", rec.withheld_rms, 0.0, math.inf, unknown=True)
    out += _in("backlash.payload_kg", rec.payload_kg, 0.0, MAX_PAYLOAD_KG)
    for name, notes in (("undetermined", rec.undetermined),
                        ("taken_out_non_physical", rec.taken_out)):
        if len(notes) > MAX_NOTES or any(len(s) > MAX_NOTES for s in notes):
            out.append(f"{name}: expected at most {MAX_NOTES} notes of {MAX_NOTES} characters")
    return out


def _weights(sw: Any, n: int) -> list[str]:
    if len(sw) != n:
        return [f"backlash.switch_weights: {len(sw)} entries for {n} joints"]
    for k, (thr, w) in enumerate(sw, start=1):
        t, p = np.asarray(thr, dtype=float), np.asarray(w, dtype=float)
        if (t.shape != p.shape or t.ndim != 1 or t.size > MAX_SWITCHES or np.any(np.isnan(t))
                or np.any(t < 0) or not _finite(p) or np.any(p < 0)
                or float(p.sum()) > 1.0 + 1e-9):
            return [f"backlash.switch_weights[{k}]: expected as many torques >= 0 as weights "
                    f"(at most {MAX_SWITCHES}), the weights in [0, 1] summing to at most 1"]
    return []


def _backlash(rec: FinalModelRecord, n: int) -> list[str]:
    out = []
    sw = rec.backlash_switch
    if sw is not None and (len(sw) != n or not all(
            v is None or (math.isfinite(v) and v >= 0) for v in sw)):
        out.append(f"backlash.switch: expected null or {n} finite values >= 0 or nulls")
    if rec.backlash_lead is not None and len(rec.backlash_lead) != n:
        out.append(f"backlash.lead: {len(rec.backlash_lead)} flags for {n} joints")
    if rec.backlash_switch_weights is not None:
        out += _weights(rec.backlash_switch_weights, n)
    w = rec.gravity_side_weights
    if w is not None and (np.ndim(w) != 2 or len(w) != n or not 1 <= np.shape(w)[1] <= n
                          or not _finite(w)):
        out.append(f"gravity_side_weights: shape {np.shape(w)}; expected ({n}, J) finite "
                   f"values, J 1..{n} lumped mass points")
    return out


def _probe(rec: FinalModelRecord) -> list[str]:
    p = rec.probe
    if p is None:
        return []
    out = _rotation("probe.probe_rotation", p.probe_rotation)
    for name, v in (("sigma_orientation_rad", p.sigma_orientation),
                    ("sigma_position", p.sigma_position),
                    ("orientation_rms_rad", p.orientation_rms)):
        out += _in(f"probe.{name}", v, 0.0, math.inf, unknown=True)
    return out


def _against(rec: FinalModelRecord, model: Manipulator) -> list[str]:
    """The domains that need the nominal model (module doc)."""
    n = model.n
    if len(rec.axes) != n:
        return [f"axes: {len(rec.axes)} joints, the model {model.name!r} has {n}"]
    nominal = np.asarray(model.bodies, dtype=float)
    reach = float(np.sum(np.linalg.norm(nominal, axis=1)))
    u = model.length_unit
    out = []
    for q in rec.parameters:
        if q.kind == "dq" and q.effect == "joint_offset":
            lim = reach if model.prismatic[q.joint - 1] else math.pi
            if not abs(q.value) <= lim:
                out.append(f"{q.name}: joint offset {q.value:.6g}; expected at most "
                           f"{lim:.6g} {'(' + u + ', the reach)' if lim == reach else 'rad'}")
    moved = np.linalg.norm(np.asarray(rec.bodies) - nominal, axis=1)
    for k in np.flatnonzero(~(moved <= BODY_SHARE * reach)):
        out.append(f"bodies[{k}]: {moved[k]:.4g} {u} from its nominal; expected at most "
                   f"{BODY_SHARE:g} x the arm's reach ({BODY_SHARE * reach:.4g} {u})")
    t = float(np.linalg.norm(rec.base_translation))
    if not t <= BASE_REACH_FACTOR * reach:
        out.append(f"base_translation: {t:.4g} {u} from the instrument; expected at most "
                   f"{BASE_REACH_FACTOR:g} x the arm's reach ({BASE_REACH_FACTOR * reach:.4g} "
                   f"{u})")
    for lab, p in zip(rec.tool_labels, np.asarray(rec.tool_offsets), strict=True):
        d = float(np.linalg.norm(p))
        if not d <= TOOL_REACH_FACTOR * reach:
            out.append(f"tool_points[{_short(lab)}]: {d:.4g} {u} from the end effector; "
                       f"expected at most {TOOL_REACH_FACTOR:g} x the arm's reach")
    return out


def record_problems(rec: FinalModelRecord, model: Manipulator | None = None) -> list[str]:
    """Every value of ``rec`` outside its domain (module doc), one message each (empty:
    none); with ``model`` (the nominal model), also the domains that need it."""
    with np.errstate(over="ignore", invalid="ignore"):  # 1e300 squared: inf, refused
        out = _arrays(rec) + _scalars(rec)
        if out:  # the rest needs the shapes
            return out
        n = len(rec.axes)
        out = _parameters(rec, n) + _backlash(rec, n) + _probe(rec)
        return out if out or model is None else _against(rec, model)
