"""Patch an MJCF file with a calibrated geometry: the same file, only the chain changed.

The counterpart of :func:`zrp.model.urdf_patch.patch_urdf` for a robot imported from MJCF
(:func:`mjcf.manipulator_from_mujoco`). Only these attributes change, at full double precision:

* each body on the chain that carries a joint: ``pos`` and ``quat`` (relative to its parent;
  other orientation attributes are removed) so that its joint's anchor is the calibrated joint
  point p'_k and its frame keeps its nominal world orientation at qpos = 0, turned by
  ``rotations[k]`` when given; the joint's ``axis`` becomes u'_k in that frame (its ``pos`` in
  the body is kept);
* the end site's ``pos`` and ``quat`` (or, without a site, the end body's, its joint's ``pos``
  moved onto the calibrated axis) so that its frame is the calibrated end point and hand frame.

Everything else (bodies without joints, geoms, meshes, inertias, limits, actuators, defaults,
names) is the file's own text. The forward kinematics depends only on the joints' world axes
and anchors at qpos = 0 and the end frame, so MuJoCo reproduces the calibrated FK to rounding.
Refused, naming the cause: ``<include>`` or ``<frame>`` elements (the chain's frames would not
be this file's), a chain body with more than one joint, an unnamed chain body or joint.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mjcf.errors import MJCFImportError
from mjcf.importer import _chain_joints, _end_body, _name, load_mujoco_model
from zrp.arrays import F64
from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.export import side_document
from zrp.calibration.validation import validate_calibration
from zrp.errors import ModelError
from zrp.jsonio import dumps
from zrp.model.manipulator import Manipulator, hand_frame
from zrp.output import check_writable, write_text
from zrp.textio import read_text
from zrp.units import metres_per_unit
from zrp.xmlio import XMLDocument, xml_document

__all__ = ["export_mjcf", "patch_mjcf", "relocate_assets"]

_ORIENTATION = ("quat", "euler", "axisangle", "xyaxes", "zaxis")


def _fmt(v: ArrayLike) -> str:
    return " ".join(repr(float(x)) for x in np.asarray(v, dtype=float).ravel())


def _pose(r: F64, t: F64) -> F64:
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, t
    return out


def _quat(r: F64) -> F64:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(r).ravel())
    return q


def _set_pose(el: ET.Element, rel: F64) -> None:
    for a in _ORIENTATION:
        el.attrib.pop(a, None)
    el.set("pos", _fmt(rel[:3, 3]))
    el.set("quat", _fmt(_quat(rel[:3, :3])))


def _rel(m: mujoco.MjModel, b: int) -> F64:
    """A body's compiled pose in its parent (4x4, metres)."""
    r = np.empty(9)
    mujoco.mju_quat2Mat(r, m.body_quat[b])
    return _pose(r.reshape(3, 3), np.array(m.body_pos[b]))


def _elements(root: ET.Element, tag: str) -> dict[str, ET.Element]:
    return {el.get("name", ""): el for el in root.iter(tag) if el.get("name")}


def _check_file(root: ET.Element, src: str) -> None:
    for tag in ("include", "frame"):
        if root.find(f".//{tag}") is not None:
            raise MJCFImportError(f"{src}: has <{tag}> elements; patch a single-file MJCF "
                                  "without <frame> (expand it first)")


#: the compiler attribute that locates each asset element's ``file`` (assetdir the fallback).
_ASSET_DIR = {"mesh": "meshdir", "skin": "meshdir", "texture": "texturedir", "hfield": "assetdir"}


def relocate_assets(root: ET.Element, src_dir: Path, out_dir: Path) -> None:
    """Keep relative asset paths pointing at the same files when the MJCF moves from
    ``src_dir`` to ``out_dir``: the compiler's meshdir/texturedir/assetdir, else each asset's
    ``file`` (absolute paths stay)."""
    def moved(value: str) -> str:
        if os.path.isabs(value):
            return value
        return os.path.relpath(os.path.join(src_dir, value), out_dir)

    dirs: set[str] = set()
    for comp in root.iter("compiler"):
        for attr in ("meshdir", "texturedir", "assetdir"):
            if comp.get(attr) is not None:
                comp.set(attr, moved(comp.get(attr, "")))
                dirs.add(attr)
    for tag, attr in _ASSET_DIR.items():
        if attr in dirs or "assetdir" in dirs:
            continue
        for el in root.iter(tag):
            if el.get("file"):
                el.set("file", moved(el.get("file", "")))


@dataclass
class _Chain:
    """What the chain's rewrite needs: the compiled model at qpos = 0, the end body and site,
    the joints, the XML elements by name and the calibrated targets (metres)."""

    src: str
    m: mujoco.MjModel
    d: mujoco.MjData
    bid: int
    sid: int
    joints: list[int]
    names: list[str]
    doc: XMLDocument
    pts: F64            # p'_1..p'_n and the end point, (n + 1, 3)
    end: F64            # the end frame, 4x4
    rot: F64 | None

    @property
    def root(self) -> ET.Element:
        """The file's root element (rewritten in place)."""
        return self.doc.root

    def bodies(self) -> list[int]:
        """Bodies from the first below the world down to the end body."""
        out, b = [], self.bid
        while b > 0:
            out.append(b)
            b = int(self.m.body_parentid[b])
        return out[::-1]


def _load(path: str | os.PathLike[str], model: Manipulator, site: str | None,
          body: str | None, rotations: ArrayLike | None) -> _Chain:
    src = str(path)
    m = load_mujoco_model(path)
    bid, sid = _end_body(m, site, body)
    joints = _chain_joints(m, bid)
    names = [_name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    if model.n != len(joints) or list(model.joint_names) != names:
        raise ModelError(f"{src}: the model's joints {list(model.joint_names)} are not the "
                         f"chain's joints {names}; patch the file the model was imported from")
    doc = xml_document(path, label=src, error=MJCFImportError)  # comments, PIs kept
    _check_file(doc.root, src)
    rot = None if rotations is None else np.asarray(rotations, dtype=float)
    if rot is not None and rot.shape != (model.n, 3, 3):
        raise ModelError(f"rotations: expected shape ({model.n}, 3, 3), got {rot.shape}")
    d = mujoco.MjData(m)
    d.qpos[:] = 0.0
    mujoco.mj_kinematics(m, d)
    pts = np.cumsum(np.asarray(model.bodies), axis=0) * metres_per_unit(model.length_unit)
    ee = model.end_effector
    end = _pose(hand_frame(ee.axial, ee.transverse), pts[-1])
    return _Chain(src, m, d, bid, sid, joints, names, doc, pts, end, rot)


def _rewrite(c: _Chain, model: Manipulator) -> F64:
    """Rewrite the chain's bodies and joints; the end body's world frame after it."""
    bodies_el, joints_el = _elements(c.root, "body"), _elements(c.root, "joint")
    t = np.eye(4)
    k = 0
    for b in c.bodies():
        bname = _name(c.m, mujoco.mjtObj.mjOBJ_BODY, b)
        nj = int(c.m.body_jntnum[b])
        if nj == 0 and not (b == c.bid and c.sid < 0):
            t = t @ _rel(c.m, b)
            continue
        if nj > 1 or bname not in bodies_el or (nj and c.names[k] not in joints_el):
            raise MJCFImportError(f"{c.src}: body {bname!r} on the chain needs a name and at "
                                  f"most one joint (it has {nj})")
        if nj == 0:                       # a rigid end body: the end frame
            _set_pose(bodies_el[bname], np.linalg.inv(t) @ c.end)
            t = c.end
            continue
        r = c.d.xmat[b].reshape(3, 3)
        r = r if c.rot is None else c.rot[k] @ r
        jel = joints_el[c.names[k]]
        want = _pose(r, c.pts[k] - r @ np.array(c.m.jnt_pos[c.joints[k]]))
        if b == c.bid and c.sid < 0:      # the end body carries the end frame
            want = c.end
            jel.set("pos", _fmt(c.end[:3, :3].T @ (c.pts[k] - c.end[:3, 3])))
        _set_pose(bodies_el[bname], np.linalg.inv(t) @ want)
        jel.set("axis", _fmt(want[:3, :3].T @ np.asarray(model.axes[k])))
        t = want
        k += 1
    return t


def patch_mjcf(path: str | os.PathLike[str], model: Manipulator, *, site: str | None = None,
               body: str | None = None, rotations: ArrayLike | None = None,
               out_dir: str | os.PathLike[str] | None = None) -> str:
    """The MJCF file ``path`` with the geometry of ``model`` (a calibrated version of the chain
    imported from it with the same ``site`` / ``body``, same joint names).

    ``out_dir``: the folder the result will be written to (relative asset paths are rewritten
    to reach the same files, :func:`relocate_assets`); default the source's folder.

    Raises:
        MJCFImportError: a file this cannot patch (see the module doc).
        ModelError: the model is not that chain.
    """
    c = _load(path, model, site, body, rotations)
    t = _rewrite(c, model)
    if c.sid >= 0:
        sname = _name(c.m, mujoco.mjtObj.mjOBJ_SITE, c.sid)
        sites = _elements(c.root, "site")
        if sname not in sites:
            raise MJCFImportError(f"{c.src}: the end site needs a name")
        _set_pose(sites[sname], np.linalg.inv(t) @ c.end)
    if out_dir is not None:
        relocate_assets(c.root, Path(path).resolve().parent, Path(out_dir).resolve())
    ET.indent(c.root, space="  ")
    return c.doc.text("patched by zrp-accuracy: the calibrated chain (body poses, joint axes, "
                      "end frame)")


def export_mjcf(cal: CalibratedRobot, source: str | os.PathLike[str], xml_path: str | Path,
                side_path: str | Path, *, site: str | None = None, body: str | None = None,
                overwrite: bool = False) -> tuple[Path, Path]:
    """Write the calibrated MJCF (``source`` patched, :func:`patch_mjcf`, its offsets folded
    into the body poses) and the side file of the terms it cannot hold
    (:func:`zrp.calibration.export.side_document`).

    Raises:
        ImplausibleValueError: a value outside its physical domain (nothing is written).
        OutputExistsError: a file exists and ``overwrite`` is False.
    """
    check_writable([xml_path, side_path], overwrite)
    validate_calibration(cal, cal.widen, "export")
    text = patch_mjcf(source, cal.model, site=site, body=body, rotations=cal.fold_rotations(),
                      out_dir=Path(xml_path).resolve().parent)
    try:
        original = read_text(source, error=MJCFImportError)
    except (OSError, UnicodeDecodeError) as exc:
        raise MJCFImportError(f"{source}: cannot read ({exc})") from exc
    side = side_document(cal, Path(xml_path).name, original, None, site or body)
    x = write_text(xml_path, text, overwrite=overwrite)
    s = write_text(side_path, dumps(side), overwrite=overwrite)
    return x, s
