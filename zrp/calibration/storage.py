"""Write and read a calibrated robot: a model TOML (geometry) and a compensation JSON.

The compensation file (``schema_version`` 1, lengths in the model's ``length_unit``, angles
in rad) holds everything the model file cannot: the nominal model, the instrument-from-base
transform, the tool points in full, the folded offsets, the joint map, thermal expansion,
the backlash flank model and, after a full-pose fit, the probe rotation and noise weights;
its keys are documented in zrp/calibration/README.md.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.jointmap import Term
from zrp.errors import InputError
from zrp.gap.fit.fullpose import FullPoseFit
from zrp.jsonio import dumps
from zrp.model.files import dumps_model, load_model, loads_model
from zrp.output import check_writable, write_text
from zrp.rotations import er_from_matrix, rotvec_from_er
from zrp.version import __version__

__all__ = ["SCHEMA_VERSION", "calibration_document", "full_pose_document", "read_calibration",
           "write_calibration"]

SCHEMA_VERSION = 1


def full_pose_document(fp: FullPoseFit | None) -> dict[str, Any] | None:
    """The ``full_pose`` entry: the probe rotation R_t (probe frame in the hand frame) and the
    noise weights of a full-pose fit (:mod:`zrp.gap.fit.fullpose`); None without one."""
    if fp is None or not fp.orientation:
        return None
    rt = np.asarray(fp.probe_rotation)
    return {"probe_rotation": rt.tolist(),
            "probe_rotvec_rad": rotvec_from_er(er_from_matrix(rt)).tolist(),
            "sigma_orientation_rad": fp.sigma_orientation,
            "sigma_orientation_source": "given" if fp.sigma_orientation_given else "estimated",
            "sigma_position": fp.sigma_position,
            "orientation_rms_rad": fp.orientation_rms}


def calibration_document(cal: CalibratedRobot, model_file: str,
                         full_pose: FullPoseFit | None = None) -> dict[str, Any]:
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
            cal.backlash_switch), "payload_kg": cal.payload_kg},
        "gravity_dir": list(cal.gravity_dir),
        "harmonics": list(cal.harmonics),
        "compliance_model": cal.compliance_model,
        "withheld_rms": cal.withheld_rms,
        "gravity_side_weights": (None if cal.gravity_side_weights is None
                                 else np.asarray(cal.gravity_side_weights).tolist()),
        "full_pose": full_pose_document(full_pose),
        "apply": ("x = q + sum(value * basis) per joint-map term; position of tool point j "
                  "= R_b (p'(x) + R'_n(x) t'_j) + t_b with p', R'_n the forward kinematics of "
                  "model_file, bodies scaled by 1 + kappa (temp - t_ref)"),
    }


def write_calibration(cal: CalibratedRobot, model_path: str | Path, comp_path: str | Path, *,
                      overwrite: bool = False, full_pose: FullPoseFit | None = None
                      ) -> tuple[Path, Path]:
    """Write the calibrated model (TOML) and the compensation file (JSON), atomically; both
    names are checked before either is written. ``full_pose``: the full-pose fit of ``cal``
    (its probe rotation and orientation noise go to the file's ``full_pose``).

    Raises:
        OutputExistsError: a file exists and ``overwrite`` is False.
    """
    check_writable([model_path, comp_path], overwrite)
    doc = calibration_document(cal, Path(model_path).name, full_pose)
    m = write_text(model_path, f"# written by zrp-accuracy {__version__}\n"
                   + dumps_model(cal.model), overwrite=overwrite)
    c = write_text(comp_path, dumps(doc), overwrite=overwrite)
    return m, c


def _get(doc: dict[str, Any], key: str, src: str) -> Any:
    if key not in doc:
        raise InputError(f"{src}: missing key {key!r}")
    return doc[key]


def read_calibration(comp_path: str | Path, model_path: str | Path | None = None
                     ) -> CalibratedRobot:
    """Read a calibrated robot back (``model_path`` default: the ``model_file`` named in the
    compensation file, beside it).

    Raises:
        InputError: unreadable file, wrong schema or missing keys (naming the file and key).
    """
    src = str(comp_path)
    try:
        doc = json.loads(Path(comp_path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"{src}: cannot read the compensation file: {exc}") from exc
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputError(f"{src}: schema_version {doc.get('schema_version')!r}, expected "
                         f"{SCHEMA_VERSION}")
    mpath = (Path(comp_path).parent / _get(doc, "model_file", src) if model_path is None
             else Path(model_path))
    tools = _get(doc, "tool_points", src)
    bl = _get(doc, "backlash", src)
    th = _get(doc, "thermal", src)
    return CalibratedRobot(
        load_model(mpath), loads_model(_get(doc, "nominal_model", src), f"{src}: nominal_model"),
        np.array(_get(doc, "base_rotation", src), dtype=float),
        np.array(_get(doc, "base_translation", src), dtype=float), tuple(tools),
        np.array([tools[k] for k in tools], dtype=float).reshape(-1, 3),
        np.array(_get(doc, "joint_offsets_folded", src), dtype=float),
        tuple(Term.from_dict(t, f"{src}: joint_map[{i}]")
              for i, t in enumerate(_get(doc, "joint_map", src))),
        float(th["kappa"]), float(th["t_ref_degC"]),
        None if bl["switch"] is None else tuple(bl["switch"]), float(bl["payload_kg"]),
        tuple(_get(doc, "gravity_dir", src)), tuple(_get(doc, "harmonics", src)),
        _get(doc, "frame", src), _get(doc, "compliance_model", src), doc.get("withheld_rms"),
        None if doc.get("gravity_side_weights") is None
        else np.array(doc["gravity_side_weights"], dtype=float))
