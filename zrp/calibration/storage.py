"""Write and read a calibrated robot: a model TOML (geometry) and a compensation JSON.

The compensation file (``schema_version`` 3, lengths in the model's ``length_unit``, angles
in rad; version 3 adds ``model_sha256``, the SHA-256 of the model file, which names the
compensation file's own hash in turn (:mod:`zrp.calibration.filecheck`); versions 1 and 2 are
read with a warning that the pair cannot be checked; version 1, written by 0.3.0 and earlier,
has no ``backlash.lead``, so every joint lags behind its approach) holds everything the
model file cannot: the nominal model, the instrument-from-base transform, the tool points in
full, the folded offsets, the joint map, thermal expansion, the backlash flank model and,
after a full-pose fit, the probe rotation and noise weights, and the learned residual term
(``learned_residual``, :mod:`zrp.calibration.learned`: plain arrays, null without one); its
keys are documented in zrp/calibration/README.md.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.conditions import Conditions
from zrp.calibration.filecheck import (
    FieldDomainError,
    bind_pair,
    check_fields,
    check_pair,
)
from zrp.calibration.jointmap import Term
from zrp.calibration.learned import LearnedTerm
from zrp.calibration.schema import check_schema
from zrp.calibration.validation import validate_calibration
from zrp.errors import InputError, ZRPError
from zrp.escape import one_line
from zrp.gap.finalrecord import ProbeRecord, switch_weights
from zrp.gap.fit.fullpose import FullPoseFit
from zrp.jsonio import MAX_COMPENSATION_BYTES, dumps, read_json, to_jsonable, version_field
from zrp.model.files import dumps_model, load_model, loads_model
from zrp.model.manipulator import Manipulator
from zrp.output import check_writable, write_text
from zrp.rotations import er_from_matrix, rotvec_from_er
from zrp.version import __version__

__all__ = ["SCHEMA_VERSION", "calibration_document", "full_pose_document", "model_file_path",
           "read_calibration", "write_calibration"]

SCHEMA_VERSION = 3
#: the versions this reader understands (1: no ``backlash.lead``; 1, 2: no hashes)
READABLE_VERSIONS = (1, 2, 3)


def full_pose_document(fp: FullPoseFit | ProbeRecord | None,
                       fold: ArrayLike | None = None) -> dict[str, Any] | None:
    """The ``full_pose`` entry: the probe rotation R_t (probe frame in the calibrated model's
    hand frame) and the noise weights of a full-pose fit (:mod:`zrp.gap.fit.fullpose`); None
    without one.

    ``fold``: R_fold, shape (3, 3), the rotation the calibrated model's folded joint offsets
    give its hand frame (:meth:`CalibratedRobot.fold_rotations`, last joint). The fit's R_t is
    in the fitted model's hand frame, R'_n R_fold of the calibrated one, so the file carries
    R_fold R_t: ``predict_rotation(q) @ probe_rotation`` is then the probe's orientation."""
    if fp is None or not fp.orientation:
        return None
    rt = np.asarray(fp.probe_rotation)
    if fold is not None:
        rt = np.asarray(fold, dtype=float) @ rt
    return {"probe_rotation": rt.tolist(),
            "probe_rotvec_rad": rotvec_from_er(er_from_matrix(rt)).tolist(),
            "sigma_orientation_rad": fp.sigma_orientation,
            "sigma_orientation_source": "given" if fp.sigma_orientation_given else "estimated",
            "sigma_position": fp.sigma_position,
            "orientation_rms_rad": fp.orientation_rms}


def calibration_document(cal: CalibratedRobot, model_file: str,
                         full_pose: FullPoseFit | ProbeRecord | None = None) -> dict[str, Any]:
    """The compensation file's JSON document (see the module doc); ``full_pose``: the
    full-pose fit the calibration came from (its probe rotation and noise are recorded)."""
    return {
        "schema_version": SCHEMA_VERSION,
        "zrp_version": __version__,
        "kind": "zrp calibration (non-geometric part and registration)",
        "model_file": model_file,
        "length_unit": cal.model.length_unit,
        "nominal_model": dumps_model(cal.nominal),
        "frame": cal.frame,
        "base_rotation": np.asarray(cal.base_rotation).tolist(),
        "base_rotvec": rotvec_from_er(er_from_matrix(np.asarray(cal.base_rotation))).tolist(),
        "base_translation": np.asarray(cal.base_translation).tolist(),
        "tool_points": {lab: np.asarray(t).tolist()
                        for lab, t in zip(cal.tool_labels, cal.tool_points, strict=True)},
        "joint_offsets_folded": np.asarray(cal.joint_offsets).tolist(),
        "joint_map": [t.to_dict() for t in cal.terms],
        "thermal": {"kappa": cal.kappa, "t_ref_degC": cal.t_ref},
        "backlash": {"switch": None if cal.backlash_switch is None else list(
            cal.backlash_switch), "payload_kg": cal.payload_kg,
                     "lead": None if cal.backlash_lead is None else list(cal.backlash_lead),
                     "switch_weights": cal.backlash_switch_weights},
        "gravity_dir": list(cal.gravity_dir),
        "harmonics": list(cal.harmonics),
        "compliance_model": cal.compliance_model,
        "withheld_rms": cal.withheld_rms,
        "gravity_side_weights": (None if cal.gravity_side_weights is None
                                 else np.asarray(cal.gravity_side_weights).tolist()),
        "full_pose": full_pose_document(full_pose, cal.fold_rotations()[-1]),
        "conditions": None if cal.conditions is None else cal.conditions.to_dict(),
        "domains_widened": cal.widen,
        "undetermined": list(cal.undetermined),
        "taken_out_non_physical": list(cal.taken_out),
        "learned_residual": None if cal.learned is None else cal.learned.to_dict(),
        "apply": ("x = q + sum(value * basis) per joint-map term; position of tool point j "
                  "= R_b (p'(x) + R'_n(x) t'_j) + t_b with p', R'_n the forward kinematics of "
                  "model_file, bodies scaled by 1 + kappa (temp - t_ref); with learned_residual, "
                  "the hand then moves by its rigid fit to -f(q) (learned_residual.evaluate)"),
    }


#: the first words of the line that marks a calibrated model TOML (:func:`calibrated_marker`)
CALIBRATED_MARKER = "# zrp calibrated model"


def calibrated_marker(text: str) -> str | None:
    """The compensation file a calibrated model TOML names in its marker line, or None when
    ``text`` is not a calibrated model's."""
    for line in text.splitlines()[:3]:
        if line.startswith(CALIBRATED_MARKER):
            return line.split("compensation file ", 1)[-1].split(";", 1)[0].strip() or None
    return None


def _toml_header(cal: CalibratedRobot, comp_name: str) -> str:
    """Comment lines heading the model TOML: the marker naming its compensation file, the
    version and the conditions (the model format has no keys for them; compensation.json
    carries them as data). The user's strings (the file names, the instrument) pass through
    :func:`zrp.escape.one_line`: a name with a line break cannot end the comment and add TOML
    keys."""
    comp_name = one_line(comp_name)
    lines = [f"{CALIBRATED_MARKER}: the geometry only; its joint map, thermal expansion and "
             f"registration are in the compensation file {comp_name}; export it whole with "
             f"zrp export --calibration {comp_name}",
             f"# written by zrp-accuracy {__version__}"]
    c = cal.conditions
    if c is not None:
        lines += ["# calibrated under (compensation.json 'conditions'):",
                  f"#   payloads_kg = {list(c.payloads_kg) if c.payloads_kg is not None else None}"
                  f"; tool_points = {list(c.tool_points)}",
                  f"#   temp_range_degC = {c.temp_range_degC}; length_unit = {c.length_unit};"
                  f" angle_unit = {c.angle_unit}",
                  f"#   instrument = {one_line(c.instrument)}; data_file = "
                  f"{one_line(c.data_file)}; "
                  f"data_sha256 = {c.data_sha256}"]
    if cal.learned is not None:
        t = cal.learned
        lines += ["# LEARNED RESIDUAL TERM (compensation.json 'learned_residual'): kernel ridge "
                  f"on (sin q, cos q) of {', '.join(t.inputs)};",
                  f"#   withheld RMS {t.withheld_rms_physical:.4g} (physical model) -> "
                  f"{t.withheld_rms_hybrid:.4g} {cal.model.length_unit} with it; valid within "
                  "its training ranges only"]
    if cal.undetermined:
        lines.append("# NOT DETERMINED by the data (kept at nominal or known only loosely; "
                     "compensation.json 'undetermined'):")
        lines += [f"#   {' '.join(u.split())}" for u in cal.undetermined]
    if cal.taken_out:
        lines.append("# TAKEN OUT as non-physical (outside their physical domains, held at "
                     "nominal; lumped compliance weights whose sum left its domain held at "
                     "sum 0; compensation.json 'taken_out_non_physical'):")
        lines += [f"#   {one_line(' '.join(u.split()))}" for u in cal.taken_out]
    return "\n".join(lines) + "\n"


def write_calibration(cal: CalibratedRobot, model_path: str | Path, comp_path: str | Path, *,
                      overwrite: bool = False,
                      full_pose: FullPoseFit | ProbeRecord | None = None
                      ) -> tuple[Path, Path]:
    """Write the calibrated model (TOML) and the compensation file (JSON), atomically; both
    names are checked before either is written. ``full_pose``: the full-pose fit of ``cal``
    (its probe rotation and orientation noise go to the file's ``full_pose``). The model file
    must sit in the compensation file's folder or below it (``model_file`` is relative).

    Raises:
        OutputExistsError: a file exists and ``overwrite`` is False.
        FieldDomainError: a field the reader would refuse
            (:func:`zrp.calibration.filecheck.check_fields`); nothing is written.
        ImplausibleValueError: a value outside its physical domain
            (:func:`zrp.calibration.validation.validate_calibration`); nothing is written.
    """
    check_fields(cal, cal.model.length_unit, "write_calibration")  # the reader's checks
    validate_calibration(cal, cal.widen, "write_calibration")
    check_writable([model_path, comp_path], overwrite)
    folder = Path(comp_path).resolve().parent
    try:
        rel = Path(model_path).resolve().relative_to(folder).as_posix()
    except ValueError:
        raise InputError(f"model_path: {model_path} is not in the folder of {comp_path} (or "
                         "below it); the compensation file names its model relative to "
                         "itself") from None
    doc, toml = bind_pair(to_jsonable(calibration_document(cal, rel, full_pose)),
                          _toml_header(cal, Path(comp_path).name) + dumps_model(cal.model))
    m = write_text(model_path, toml, overwrite=overwrite)
    c = write_text(comp_path, dumps(doc), overwrite=overwrite)
    return m, c


def _get(doc: dict[str, Any], key: str, src: str) -> Any:
    if key not in doc:
        raise InputError(f"{src}: missing key {key!r}")
    return doc[key]


def model_file_path(comp_path: str | Path, model_file: object, *,
                    allow_outside: bool = False) -> Path:
    """The model file named by a compensation file: ``model_file`` relative to the
    compensation file's folder. An absolute path, or one that leaves that folder (``..``, a
    symbolic link out), is refused unless ``allow_outside``.

    Raises:
        InputError: naming the compensation file, the path and why it is refused.
    """
    src = str(comp_path)
    if not isinstance(model_file, str) or not model_file.strip() or "\0" in model_file:
        raise InputError(f"{src}: model_file: expected a file name relative to the "
                         f"compensation file, got {model_file!r}")
    folder = Path(comp_path).parent
    path = Path(model_file)
    if allow_outside:
        return path if path.is_absolute() else folder / path
    if path.is_absolute() or path.drive or path.root:
        raise InputError(f"{src}: model_file {model_file!r} is an absolute path; it must be "
                         "relative to the compensation file's folder (pass the model file "
                         "explicitly, model_path= (--model-file on the command line), or "
                         "allow_outside=True to accept it)")
    full = folder / path
    try:
        full.resolve().relative_to(folder.resolve())
    except (ValueError, OSError, RuntimeError):
        raise InputError(f"{src}: model_file {model_file!r} leaves the compensation file's "
                         "folder; it must stay in it or below (pass the model file "
                         "explicitly, model_path= (--model-file on the command line), or "
                         "allow_outside=True to accept it)") from None
    return full


def read_calibration(comp_path: str | Path, model_path: str | Path | None = None, *,
                     allow_outside: bool = False) -> CalibratedRobot:
    """Read a calibrated robot back (``model_path`` default: the ``model_file`` named in the
    compensation file, relative to it, :func:`model_file_path`), validated like a written one.

    Raises:
        InputError: unreadable file, wrong schema, missing or malformed keys (naming the file
            and key), a model_file outside the compensation file's folder.
        ImplausibleValueError: a value outside its physical domain.
    """
    src = str(comp_path)
    # a regular file, its size checked before parsing; nesting bounded (zrp.jsonio)
    doc = read_json(comp_path, label=src, max_bytes=MAX_COMPENSATION_BYTES,
                    what="compensation file")
    if not isinstance(doc, dict):
        raise InputError(f"{src}: expected a JSON object")
    version = version_field(doc, "schema_version", READABLE_VERSIONS, src=src,
                            hint=f" (a file from a newer zrp-accuracy? zrp_version "
                                 f"{str(doc.get('zrp_version'))[:40]!r})")
    check_schema(doc, version, src)  # by what the file holds (zrp.calibration.schema)
    mpath = (model_file_path(comp_path, _get(doc, "model_file", src),
                             allow_outside=allow_outside)
             if model_path is None else Path(model_path))
    model = load_model(mpath)
    check_pair(doc, src, mpath, _bytes(mpath))
    try:
        cal = _robot(doc, model, src)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError) as exc:
        if isinstance(exc, ZRPError):
            raise
        raise InputError(f"{src}: malformed compensation file ({type(exc).__name__}: "
                         f"{exc})") from None
    check_fields(cal, doc.get("length_unit"), src)
    validate_calibration(cal, cal.widen, src)
    return cal


def _bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()  # load_model checked it: a regular file of bounded size
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from exc


def _robot(doc: dict[str, Any], model: Manipulator, src: str) -> CalibratedRobot:
    tools = _get(doc, "tool_points", src)
    bl = _get(doc, "backlash", src)
    th = _get(doc, "thermal", src)
    return CalibratedRobot(
        model, loads_model(str(_get(doc, "nominal_model", src)), f"{src}: nominal_model"),
        np.array(_get(doc, "base_rotation", src), dtype=float),
        np.array(_get(doc, "base_translation", src), dtype=float), tuple(tools),
        np.array([tools[k] for k in tools], dtype=float).reshape(-1, 3),
        np.array(_get(doc, "joint_offsets_folded", src), dtype=float),
        tuple(Term.from_dict(t, f"{src}: joint_map[{i}]")
              for i, t in enumerate(_get(doc, "joint_map", src))),
        float(th["kappa"]), float(th["t_ref_degC"]),
        None if bl["switch"] is None else tuple(None if v is None else float(v)
                                                for v in bl["switch"]),
        float(bl["payload_kg"]),
        tuple(float(v) for v in _get(doc, "gravity_dir", src)),
        tuple(int(h) for h in _get(doc, "harmonics", src)),
        str(_get(doc, "frame", src)), str(_get(doc, "compliance_model", src)),
        **_optional_fields(doc, bl, src))


def _optional_fields(doc: dict[str, Any], bl: dict[str, Any], src: str) -> dict[str, Any]:
    """The fields a compensation.json may leave out or set to null (older versions)."""
    cond = doc.get("conditions")
    widen = doc.get("domains_widened")
    gsw = doc.get("gravity_side_weights")
    return {
        "withheld_rms": None if doc.get("withheld_rms") is None else float(doc["withheld_rms"]),
        "gravity_side_weights": None if gsw is None else np.array(gsw, dtype=float),
        "conditions": None if cond is None else Conditions.from_dict(cond, f"{src}: conditions"),
        "widen": None if widen is None else {str(k): float(v) for k, v in dict(widen).items()},
        "backlash_lead": _lead(bl.get("lead"), src),
        "undetermined": tuple(str(u) for u in doc.get("undetermined") or ()),
        "taken_out": tuple(str(u) for u in doc.get("taken_out_non_physical") or ()),
        "backlash_switch_weights": switch_weights(bl.get("switch_weights")),
        "learned": _learned(doc.get("learned_residual"), src)}


def _learned(value: Any, src: str) -> LearnedTerm | None:
    """learned_residual: null (none; every file before 0.5.0) or the term, each field in its
    domain (finite, shapes, ordered ranges)."""
    if value is None:
        return None
    try:
        return LearnedTerm.from_dict(value, src)
    except InputError as exc:
        raise FieldDomainError(f"{exc}; refused") from None


def _lead(value: Any, src: str) -> tuple[bool, ...] | None:
    """backlash.lead: null (lagging everywhere; files before 0.4.0) or one true/false per
    joint."""
    if value is None:
        return None
    if not isinstance(value, list) or not all(isinstance(v, bool) for v in value):
        raise InputError(f"{src}: backlash.lead: expected null or a list of true/false, one "
                         f"per joint, got {str(value)[:80]}")
    return tuple(value)
