"""The calibration files' fields, each in its domain, and the pair bound by hashes.

:func:`zrp.calibration.read_calibration` reads ``compensation.json`` through
:func:`loads_bounded` (JSON nested at most :data:`MAX_JSON_DEPTH` deep: a file nested 1e5 deep
is refused by name, not a ``RecursionError``) and checks the robot it describes with
:func:`field_problems` before it is used (the physical domains of the identified values are
:mod:`zrp.calibration.validation`'s). The domains:

* ``base_rotation``: a proper rotation (orthonormal to :data:`ROTATION_TOL`, determinant +1: a
  reflection is refused); ``base_translation``: finite, at most :data:`BASE_REACH_FACTOR`
  times the arm's reach from the instrument; every tool point at most
  :data:`TOOL_REACH_FACTOR` times the reach from the end effector. The reach is the sum of
  the nominal model's body lengths (length unit).
* ``length_unit`` (file and conditions): a unit of :data:`zrp.units.LENGTH_UNITS`, the same
  as the model file's (a ``calibrated.toml`` switched to metres is refused).
* ``harmonics``: whole numbers 1..:data:`MAX_HARMONIC` (as the diagnosis's options), unique.
* ``thermal.t_ref_degC`` finite, in :data:`TEMP_RANGE_DEGC`; ``gravity_dir`` a unit vector;
  ``backlash.payload_kg`` and ``backlash.switch`` finite, payload 0..:data:`MAX_PAYLOAD_KG`;
  ``withheld_rms`` finite and >= 0; ``gravity_side_weights`` finite, shape (n, J) with J the
  lumped mass points of the nominal model.
* ``conditions``: payloads 0..:data:`MAX_PAYLOAD_KG`, a temperature range ordered and within
  :data:`TEMP_RANGE_DEGC`, joint limits finite with lower < upper.

The pair: :func:`bind_pair` makes ``compensation.json`` name the SHA-256 of
``calibrated.toml``'s bytes (``model_sha256``) and ``calibrated.toml`` name, in a comment line,
the SHA-256 of the compensation document (:func:`document_sha256`: its canonical JSON without
``model_sha256``). :func:`check_pair` refuses a pair in which either file was changed, naming
the file. Files written before schema_version 3 have no hashes: read with a
:class:`PairWarning`.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.jointmap import NON_GEOMETRIC
from zrp.errors import InputError, ZRPWarning
from zrp.gap.recordcheck import (  # the same bounds as the diagnosis's final-model record
    BASE_REACH_FACTOR,
    MAX_HARMONIC,
    MAX_PAYLOAD_KG,
    ROTATION_TOL,
    TEMP_RANGE_DEGC,
    TOOL_REACH_FACTOR,
)
from zrp.jsonio import MAX_JSON_DEPTH, loads_json
from zrp.kinematics import forward_kinematics
from zrp.units import LENGTH_UNITS

__all__ = ["BASE_REACH_FACTOR", "MAX_HARMONIC", "MAX_JSON_DEPTH", "MAX_PAYLOAD_KG",
           "ROTATION_TOL", "TEMP_RANGE_DEGC", "TOOL_REACH_FACTOR", "FieldDomainError",
           "PairWarning", "TamperedPairError", "bind_pair", "check_fields", "check_pair",
           "document_sha256", "field_problems", "loads_bounded"]

#: the comment line of calibrated.toml that names its compensation file's hash
_TOML_HASH = re.compile(r"^# compensation_sha256 = ([0-9a-f]{64})\s*$", re.MULTILINE)
_HASH_KEY = "model_sha256"


class FieldDomainError(InputError):
    """A field of a calibration file outside its domain (the message names file and field)."""


class TamperedPairError(InputError):
    """calibrated.toml and compensation.json do not name each other's SHA-256."""


class PairWarning(ZRPWarning):
    """A calibration pair written before schema_version 3: it carries no hashes."""


def loads_bounded(text: str, src: str) -> Any:
    """``json.loads(text)`` after checking that arrays and objects nest at most
    :data:`MAX_JSON_DEPTH` deep (:func:`zrp.jsonio.loads_json`, the one bounded reader).

    Raises:
        InputError: too deep, or not JSON (naming ``src``).
    """
    return loads_json(text, src, what="compensation file")


def _reach(cal: CalibratedRobot) -> float:
    return float(np.sum(np.linalg.norm(np.asarray(cal.nominal.bodies, dtype=float), axis=1)))


def _rotation(r: np.ndarray) -> list[str]:
    if not np.all(np.isfinite(r)):
        return ["base_rotation: not every value is finite"]
    err = float(np.max(np.abs(r @ r.T - np.eye(3))))
    if err > ROTATION_TOL:
        return [f"base_rotation: not orthonormal (|R R^T - I| = {err:.3g} > {ROTATION_TOL:g})"]
    if np.linalg.det(r) < 0:
        return ["base_rotation: a reflection (determinant -1), not a rotation"]
    return []


def _lengths(cal: CalibratedRobot) -> list[str]:
    out = _rotation(np.asarray(cal.base_rotation, dtype=float))
    reach = _reach(cal)
    u = cal.model.length_unit
    t = float(np.linalg.norm(np.asarray(cal.base_translation, dtype=float)))
    if not t <= BASE_REACH_FACTOR * reach:
        out.append(f"base_translation: {t:.4g} {u} from the instrument; expected at most "
                   f"{BASE_REACH_FACTOR:g} x the arm's reach ({BASE_REACH_FACTOR * reach:.4g} {u})")
    for lab, p in zip(cal.tool_labels, np.asarray(cal.tool_points, dtype=float), strict=True):
        d = float(np.linalg.norm(p))
        if not d <= TOOL_REACH_FACTOR * reach:
            out.append(f"tool_points[{lab!r}]: {d:.4g} {u} from the end effector; expected "
                       f"at most {TOOL_REACH_FACTOR:g} x the arm's reach "
                       f"({TOOL_REACH_FACTOR * reach:.4g} {u})")
    return out


def _finite(name: str, v: float, lo: float, hi: float, unit: str) -> list[str]:
    return [] if lo <= v <= hi else [f"{name}: {v!r} {unit}; expected a finite value in "
                                     f"[{lo:g}, {hi:g}]"]


def _mass_points(cal: CalibratedRobot) -> int:
    """J of gravity_side_weights: the distinct points on joints 2..n and the end effector at
    q = 0 (as :meth:`zrp.gap.model.context.Context.moment_arms` merges them)."""
    zero = forward_kinematics(cal.nominal, np.zeros(cal.n))
    seen: list[np.ndarray] = []
    for j in range(1, cal.n + 1):
        pz = zero.position if j == cal.n else zero.points[j]
        if not any(np.linalg.norm(pz - s) < 1e-9 for s in seen):
            seen.append(pz)
    return len(seen)


def _scalars(cal: CalibratedRobot) -> list[str]:
    out = _finite("thermal.t_ref_degC", cal.t_ref, *TEMP_RANGE_DEGC, "degC")
    out += _finite("backlash.payload_kg", cal.payload_kg, 0.0, MAX_PAYLOAD_KG, "kg")
    g = np.asarray(cal.gravity_dir, dtype=float)
    if g.shape != (3,) or not abs(float(np.linalg.norm(g)) - 1.0) <= 1e-6:
        out.append(f"gravity_dir: {cal.gravity_dir!r}; expected a unit vector of 3 values")
    return out + _shapes(cal)


def _shapes(cal: CalibratedRobot) -> list[str]:
    out = []
    h = cal.harmonics
    if not h or len(set(h)) != len(h) or not all(1 <= v <= MAX_HARMONIC for v in h):
        out.append(f"harmonics: {list(h)[:8]!r}; expected distinct whole numbers "
                   f"1..{MAX_HARMONIC}")
    if cal.backlash_switch is not None and (
            len(cal.backlash_switch) != cal.n
            or not all(v is None or math.isfinite(v) for v in cal.backlash_switch)):
        out.append(f"backlash.switch: expected null or {cal.n} finite values or nulls")
    if cal.withheld_rms is not None:
        out += _finite("withheld_rms", cal.withheld_rms, 0.0, math.inf, cal.model.length_unit)
    w = cal.gravity_side_weights
    if w is not None:
        w = np.asarray(w, dtype=float)
        j = _mass_points(cal)
        if w.shape != (cal.n, j) or not np.all(np.isfinite(w)):
            out.append(f"gravity_side_weights: shape {w.shape}; expected ({cal.n}, {j}) "
                       "finite values (per joint and lumped mass point)")
    return out


def _conditions(cal: CalibratedRobot) -> list[str]:
    c = cal.conditions
    if c is None:
        return []
    out = []
    if c.length_unit != cal.model.length_unit:
        out.append(f"conditions.length_unit: {c.length_unit!r}, but the model's is "
                   f"{cal.model.length_unit!r}")
    for v in c.payloads_kg or ():
        out += _finite("conditions.payloads_kg", v, 0.0, MAX_PAYLOAD_KG, "kg")
    if c.temp_range_degC is not None:
        lo, hi = c.temp_range_degC
        out += _finite("conditions.temp_range_degC[0]", lo, *TEMP_RANGE_DEGC, "degC")
        out += _finite("conditions.temp_range_degC[1]", hi, *TEMP_RANGE_DEGC, "degC")
        if not lo <= hi:
            out.append(f"conditions.temp_range_degC: [{lo}, {hi}] is not ordered")
    for k, lim in enumerate(c.joint_limits, start=1):
        if lim is not None and not (math.isfinite(lim[0]) and math.isfinite(lim[1])
                                    and lim[0] < lim[1]):
            out.append(f"conditions.joint_limits[{k}]: {list(lim)}; expected finite "
                       "lower < upper")
    return out


def field_problems(cal: CalibratedRobot, length_unit: object) -> list[str]:
    """Every field of ``cal`` (read from a file whose ``length_unit`` is given) outside its
    domain (module docstring), one message each; empty: none."""
    out = []
    if not isinstance(length_unit, str) or length_unit not in LENGTH_UNITS:
        out.append(f"length_unit: {length_unit!r}; expected one of {sorted(LENGTH_UNITS)}")
    elif length_unit != cal.model.length_unit:
        out.append(f"length_unit: {length_unit!r}, but the model file's is "
                   f"{cal.model.length_unit!r} (was the model file changed?)")
    with np.errstate(over="ignore", invalid="ignore"):  # 1e300 squared: inf, refused
        return (out + _lengths(cal) + _scalars(cal) + _conditions(cal) + _offsets(cal)
                + _terms(cal) + _learned(cal))


def _offsets(cal: CalibratedRobot) -> list[str]:
    """joint_offsets_folded: finite, at most pi on a revolute joint, 0 on a prismatic one
    (its offset is a joint-map term)."""
    d = np.asarray(cal.joint_offsets, dtype=float)
    bad = [k + 1 for k in range(cal.n) if not (
        d[k] == 0.0 if cal.model.prismatic[k] else abs(d[k]) <= math.pi)]
    return [] if not bad else [f"joint_offsets_folded: joint(s) {bad} ({d[bad[0] - 1]!r}); "
                               "expected at most pi rad on a revolute joint, 0 on a prismatic "
                               "one"]


def _terms(cal: CalibratedRobot) -> list[str]:
    """joint_map: each term of a known effect, named ``q{joint}.``, finite (a prismatic
    offset within the arm's reach; cyclic terms of the file's harmonics)."""
    out = []
    for i, t in enumerate(cal.terms):
        head, _, what = t.name.partition(".")
        cyc = re.fullmatch(r"(sin|cos)([0-9]+)", what)
        if t.effect not in NON_GEOMETRIC:
            out.append(f"joint_map[{i}]: effect {t.effect!r}; expected one of "
                       f"{', '.join(NON_GEOMETRIC)}")
        elif head != f"q{t.joint}" or not what:
            out.append(f"joint_map[{i}]: name {t.name!r} is not joint {t.joint}'s")
        elif not math.isfinite(t.value) or (t.effect == "joint_offset" and not abs(
                t.value) <= (_reach(cal) if cal.model.prismatic[t.joint - 1] else math.pi)):
            out.append(f"joint_map[{i}] ({t.name}): value {t.value!r}; expected a finite "
                       "value (an offset of at most pi rad, or the arm's reach if prismatic)")
        elif t.effect == "cyclic_error" and (cyc is None or int(cyc[2]) not in cal.harmonics):
            out.append(f"joint_map[{i}] ({t.name}): not a harmonic of {list(cal.harmonics)}")
    return out


#: The learned term's worst-case bound (|mean| + sum |coef|) may exceed the arm's reach by
#: this factor: a kernel ridge on hundreds of poses has coefficients of both signs whose sum
#: is far above any correction it gives (5e4 mm on a real-size term whose corrections are
#: under 1 mm); 1e300 coefficients are still no residual.
LEARNED_SLACK = 1e4


def _learned(cal: CalibratedRobot) -> list[str]:
    """learned_residual: the largest correction it can give (|mean| + sum |coef| per output,
    the kernel is at most 1) within :data:`LEARNED_SLACK` times the arm's reach."""
    t = cal.learned
    if t is None:
        return []
    most = float(np.max(np.abs(t.mean) + np.sum(np.abs(t.coef), axis=0)))
    reach = _reach(cal)
    return [] if most <= LEARNED_SLACK * reach else [
        f"learned_residual.coef, mean: a correction of up to {most:.4g} "
        f"{cal.model.length_unit}; expected at most {LEARNED_SLACK:g} times the arm's reach "
        f"({reach:.4g})"]


def check_fields(cal: CalibratedRobot, length_unit: object, src: str) -> None:
    """Refuse ``cal`` when a field is outside its domain.

    Raises:
        FieldDomainError: naming ``src`` and every such field.
    """
    bad = field_problems(cal, length_unit)
    if bad:
        raise FieldDomainError(f"{src}: {len(bad)} field(s) outside their domain, refused: "
                               + "; ".join(bad))


def document_sha256(doc: dict[str, Any]) -> str:
    """SHA-256 of the compensation document's canonical JSON (sorted keys, no spaces), its
    ``model_sha256`` left out."""
    body = {k: v for k, v in doc.items() if k != _HASH_KEY}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def bind_pair(doc: dict[str, Any], toml_text: str) -> tuple[dict[str, Any], str]:
    """The compensation document (plain JSON values) and the model TOML text, each naming the
    other's SHA-256: the TOML gets a ``# compensation_sha256 = ...`` line after its header
    comments, the document ``model_sha256``."""
    lines = toml_text.splitlines(keepends=True)
    head = 0
    while head < len(lines) and lines[head].startswith("#"):
        head += 1
    lines.insert(head, f"# compensation_sha256 = {document_sha256(doc)}\n")
    text = "".join(lines)
    return {**doc, _HASH_KEY: hashlib.sha256(text.encode("utf-8")).hexdigest()}, text


def check_pair(doc: dict[str, Any], src: str, model_path: Path, model_bytes: bytes) -> None:
    """Refuse a pair whose files do not name each other's SHA-256 (schema_version 3 on);
    an older file is read with a :class:`PairWarning`.

    Raises:
        TamperedPairError: naming the file that was changed.
    """
    if type(doc.get("schema_version")) is int and doc["schema_version"] in (1, 2):
        warnings.warn(f"{src}: written before schema_version 3, it does not name its model "
                      f"file's SHA-256: a changed {model_path.name} cannot be detected "
                      "(calibrate again to bind the pair)", PairWarning, stacklevel=3)
        return
    named = doc.get(_HASH_KEY)
    actual = hashlib.sha256(model_bytes).hexdigest()
    if named != actual:
        raise TamperedPairError(
            f"{model_path}: its SHA-256 ({actual[:16]}...) is not the one {src} names "
            f"({str(named)[:16]}...): the model file was changed after the pair was written, "
            "or belongs to another calibration; refused")
    m = _TOML_HASH.search(model_bytes.decode("utf-8", "replace"))
    if m is None or m.group(1) != document_sha256(doc):
        raise TamperedPairError(
            f"{src}: its content is not the one {model_path} names (compensation_sha256): the "
            "compensation file was changed after the pair was written; refused")
