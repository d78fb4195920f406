"""Export a calibrated robot into the robot's own URDF: a patched copy plus a side file.

:func:`export_urdf` validates the calibration
(:func:`zrp.calibration.validation.validate_calibration`: nothing implausible is exported),
patches the URDF the robot was imported from
(:func:`zrp.model.urdf_patch.patch_urdf`: only the chain's origins and axes change; links,
names, joint types, limits, inertias, meshes and fixed frames stay) with the folded geometry,
turning each link's frame by its folded offsets (so meshes follow their link), and writes the
terms a URDF cannot hold to a side file (JSON, keys in zrp/calibration/README.md): the joint
map (encoder scale, cyclic error, compliance, backlash), thermal expansion, the
instrument-from-base transform, the tool points, the folded offsets, the conditions and the
learned residual term (:mod:`zrp.calibration.learned`; null without one).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.storage import calibration_document
from zrp.calibration.validation import validate_calibration
from zrp.errors import InputError
from zrp.jsonio import dumps
from zrp.model.urdf_patch import patch_urdf
from zrp.output import check_writable, write_text
from zrp.textio import read_text

__all__ = ["SIDE_KIND", "export_urdf", "side_document"]

SIDE_KIND = "zrp calibration side file (the terms a URDF cannot hold)"

#: keys of the compensation document that a side file repeats (the rest is the URDF's).
_SIDE_KEYS = ("schema_version", "zrp_version", "length_unit", "frame", "base_rotation",
              "base_rotvec", "base_translation", "tool_points", "joint_offsets_folded",
              "joint_map", "thermal", "backlash", "gravity_dir", "harmonics",
              "compliance_model", "gravity_side_weights", "conditions", "domains_widened",
              "learned_residual")


def side_document(cal: CalibratedRobot, urdf_file: str, source_text: str, base_link: str | None,
                  end_link: str | None) -> dict[str, Any]:
    """The side file of an exported URDF (its keys as in compensation.json, plus the URDF
    file, the source URDF's SHA-256 and the chain)."""
    doc = calibration_document(cal, urdf_file)
    out: dict[str, Any] = {"kind": SIDE_KIND, "urdf_file": urdf_file,
                           "source_urdf_sha256": hashlib.sha256(
                               source_text.encode("utf-8")).hexdigest(),
                           "chain": {"base_link": base_link, "end_link": end_link,
                                     "joints": list(cal.model.joint_names)}}
    out.update({k: doc[k] for k in _SIDE_KEYS})
    out["apply"] = ("the URDF carries the calibrated geometry (joint origins and axes; the "
                    "revolute offsets joint_offsets_folded are folded into the origins, so "
                    "commands stay the robot's own joint values); x = q + sum(value * basis) "
                    "per joint-map term (zrp/calibration/README.md), bodies scaled by 1 + kappa "
                    "(temp - t_ref), measured points m = R_b (p(x) + R_n(x) t_j) + t_b; with "
                    "learned_residual, point j is then moved by -f_j(q) (its evaluate key)")
    return out


def export_urdf(cal: CalibratedRobot, source: str | Path, urdf_path: str | Path,
                side_path: str | Path, *, base_link: str | None = None,
                end_link: str | None = None, overwrite: bool = False) -> tuple[Path, Path]:
    """Write the calibrated URDF (``source`` patched) and its side file.

    Args:
        cal: the calibrated robot (its nominal imported from ``source`` with the same
            ``base_link`` and ``end_link``).
        source: the original URDF file.
        urdf_path, side_path: the files to write (checked before any work).

    Raises:
        ImplausibleValueError: a value outside its physical domain (nothing is written).
        ModelError: the model is not the URDF's chain, or the URDF cannot carry it.
        OutputExistsError: a file exists and ``overwrite`` is False.
    """
    check_writable([urdf_path, side_path], overwrite)
    validate_calibration(cal, cal.widen, "export")
    try:
        text = read_text(source)  # a regular file, size checked, UTF-8/16
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{source}: cannot read the URDF ({exc})") from exc
    urdf = patch_urdf(text, cal.model, base_link=base_link, end_link=end_link,
                      rotations=cal.fold_rotations(), label=str(source))
    side = side_document(cal, Path(urdf_path).name, text, base_link, end_link)
    u = write_text(urdf_path, urdf, overwrite=overwrite)
    s = write_text(side_path, dumps(side), overwrite=overwrite)
    return u, s
