"""Patch a URDF with a calibrated geometry: the same file, only the chain's origins and axes
changed.

A robot imported from a URDF (:func:`zrp.model.urdf.import_urdf`) and calibrated keeps its
links, joints, names, joint types, limits, inertias, meshes, fixed frames, tool links and every
element this module does not know; only these change:

* each moving joint k on the chain base_link -> end_link: its ``<origin>`` (so that its frame
  sits at the calibrated joint point p'_k) and its ``<axis>`` (the calibrated u'_k expressed in
  that frame);
* the last joint before ``end_link`` (when it is a fixed one): its ``<origin>``, so that the
  end link's frame is the calibrated end point and hand frame (z = u'_a, y = u'_t).

Frames keep their nominal world orientation at q = 0, turned by ``rotations[k]`` when given
(e.g. the folded joint offsets, so that meshes turn with their link); the forward kinematics
depends only on the joints' world axes and points at q = 0 and the end frame (product of
exponentials, Brockett 1984), so Pinocchio and MuJoCo reproduce the calibrated model's FK to
rounding whatever the rotations. URDF's ``<calibration>`` element (homing-switch positions) is
ignored by Pinocchio and MuJoCo, so identified offsets go into the origins. A joint whose child
is ``end_link`` itself must then carry the end frame: the calibrated end point has to lie on its
axis (refused otherwise: import with a tool link behind a fixed joint).
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from zrp.arrays import F64
from zrp.errors import ModelError, ModelFileError
from zrp.model.manipulator import Manipulator, hand_frame
from zrp.model.urdf import URDFJoint, import_urdf, read_urdf, rpy_matrix
from zrp.units import metres_per_unit
from zrp.xmlio import XMLDocument, xml_document

__all__ = ["patch_urdf"]


def _num(x: float) -> str:
    return repr(float(x))


def _pose(r: F64, t: F64) -> F64:
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, t
    return out


def _set_origin(el: ET.Element, t: F64) -> None:
    org = el.find("origin")
    if org is None:
        org = ET.SubElement(el, "origin")
    with warnings.catch_warnings():  # gimbal lock: scipy still returns exact angles
        warnings.simplefilter("ignore", UserWarning)
        rpy = Rotation.from_matrix(t[:3, :3]).as_euler("xyz")  # extrinsic x-y-z = URDF rpy
    if np.abs(rpy_matrix(rpy) - t[:3, :3]).max() > 1e-12:
        raise ModelError(f"joint {el.get('name')!r}: the origin's rotation has no exact "
                         "roll-pitch-yaw")
    org.set("xyz", " ".join(_num(v) for v in t[:3, 3]))
    org.set("rpy", " ".join(_num(v) for v in rpy))


def _set_axis(el: ET.Element, a: F64) -> None:
    ax = el.find("axis")
    if ax is None:
        ax = ET.SubElement(el, "axis")
    ax.set("xyz", " ".join(_num(v) for v in a / np.linalg.norm(a)))


def _targets(model: Manipulator, nominal_world: list[F64], rotations: F64 | None,
             moving: list[int], scale: float) -> list[F64]:
    """World frames (4x4, metres) at q = 0 of the moving joints: at p'_k, turned by
    rotations[k] from their nominal orientation."""
    pts = np.cumsum(np.asarray(model.bodies)[:-1], axis=0) * scale
    out = []
    for k, i in enumerate(moving):
        r = nominal_world[i][:3, :3]
        if rotations is not None:
            r = rotations[k] @ r
        out.append(_pose(r, pts[k]))
    return out


def _end_frame(model: Manipulator, scale: float) -> F64:
    ee = model.end_effector
    p = np.sum(np.asarray(model.bodies), axis=0) * scale
    return _pose(hand_frame(ee.axial, ee.transverse), p)


def _check_same_chain(model: Manipulator, names: tuple[str, ...], src: str) -> None:
    if model.n != len(names) or tuple(model.joint_names) != names:
        raise ModelError(f"{src}: the model's joints {list(model.joint_names)} are not the "
                         f"chain's moving joints {list(names)}; patch the URDF the model was "
                         "imported from, with the same base_link and end_link")


def patch_urdf(source: str | Path, model: Manipulator, *, base_link: str | None = None,
               end_link: str | None = None, rotations: ArrayLike | None = None,
               label: str | None = None) -> str:
    """The URDF ``source`` with the geometry of ``model`` (a calibrated version of the chain
    base_link -> end_link imported from it, same joint names).

    Args:
        source: the original URDF (path or XML text).
        model: the calibrated model (any length unit).
        base_link, end_link: the chain, as given to :func:`zrp.model.urdf.import_urdf`.
        rotations: per moving joint, the rotation (3, 3) that turns its frame (and the link
            after it) from the nominal orientation, shape (n, 3, 3), or None (none).
        label: the name of XML text ``source`` in errors (the file it was read from).

    The file's comments, processing instructions and XML declaration are kept
    (:func:`zrp.xmlio.xml_document`).

    Raises:
        ModelError: the model is not that chain, or the end frame cannot be carried (see the
            module doc).
        ModelFileError: the URDF cannot be read.
    """
    imp = import_urdf(source, base_link=base_link, end_link=end_link, label=label)
    tree = read_urdf(source, label=label)
    _check_same_chain(model, imp.joints, tree.source)
    doc = xml_document(source, label=tree.source, error=ModelFileError)
    root = doc.root
    chain = tree.path(imp.base_link, imp.end_link)
    rot = None if rotations is None else np.asarray(rotations, dtype=float)
    if rot is not None and rot.shape != (model.n, 3, 3):
        raise ModelError(f"rotations: expected shape ({model.n}, 3, 3), got {rot.shape}")
    scale = metres_per_unit(model.length_unit)
    world: list[F64] = []
    t = np.eye(4)
    for j in chain:
        t = t @ j.origin
        world.append(t)
    moving = [i for i, j in enumerate(chain) if j.type != "fixed"]
    targets = dict(zip(moving, _targets(model, world, rot, moving, scale), strict=True))
    end = _end_frame(model, scale)
    elements = {el.get("name", ""): el for el in root.findall("joint")}
    _patch_chain(chain, elements, targets, end, model, scale)
    ET.indent(root, space="  ")
    note = ("patched by zrp-accuracy: the calibrated origins and axes of the chain "
            f"{imp.base_link} -> {imp.end_link}")
    if not doc.prolog.startswith("<?xml"):
        doc = XMLDocument(root, '<?xml version="1.0"?>\n' + doc.prolog, doc.epilog)
    return doc.text(note)


def _patch_chain(chain: list[URDFJoint], elements: dict[str, ET.Element],
                 targets: dict[int, F64], end: F64, model: Manipulator, scale: float) -> None:
    """Rewrite the origins (and axes) along ``chain`` so that the moving joints' frames are
    ``targets`` and the last frame is ``end`` (world, metres)."""
    t = np.eye(4)   # world frame of the current parent link, patched
    last = len(chain) - 1
    k = -1
    for i, j in enumerate(chain):
        el = elements[j.name]
        if j.type != "fixed":
            k += 1
            want = targets[i]
            if i == last:
                want = _carry_end(want, end, model, k, scale, j.name)
            _set_origin(el, np.linalg.inv(t) @ want)
            _set_axis(el, want[:3, :3].T @ np.asarray(model.axes[k]))
            t = want
        elif i == last:
            _set_origin(el, np.linalg.inv(t) @ end)
            t = end
        else:
            t = t @ j.origin


def _carry_end(want: F64, end: F64, model: Manipulator, k: int, scale: float,
               name: str) -> F64:
    """The end link is the child of the last moving joint: its frame must be the end frame,
    which is possible when the end point lies on the joint's axis."""
    u = np.asarray(model.axes[k])
    d = end[:3, 3] - want[:3, 3]
    off = np.linalg.norm(d - (d @ u) * u)
    if off > 1e-9 * max(1.0, float(np.linalg.norm(end[:3, 3]))):
        raise ModelError(f"joint {name!r}: its child is the end link, and the calibrated end "
                         f"point is {off * 1e3:.3g} mm off its axis: a URDF cannot carry it "
                         "without a new link; import the chain up to a tool link behind a "
                         "fixed joint (end_link=...)")
    return end
