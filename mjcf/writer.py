"""MJCF text and files of built arms, at full double precision.

MuJoCo's XML writer keeps 6 significant digits; :func:`mjcf_xml` rewrites the kinematic
attributes (body positions, joint axes, the end-effector site) at full precision so that a
saved file reloads to the identical kinematics. :func:`save_mjcf` writes it through the
output policy of :mod:`zrp.output` (refuses to replace without ``overwrite=True``, writes
atomically).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from mjcf.builder import BuiltArm, MJCFOptions, build, hand_quat, joint_name
from mjcf.errors import MJCFOutputError
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.output import check_writable, write_text
from zrp.xmlio import parse_xml

__all__ = ["mjcf_xml", "save_mjcf"]


def _fmt(values: ArrayLike) -> str:
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def mjcf_xml(arm: BuiltArm | Manipulator, options: MJCFOptions | None = None) -> str:
    """MJCF text of a built arm (or of a model, built with ``options``).

    MuJoCo's writer keeps 6 significant digits; the kinematic attributes (body positions, joint
    axes and ranges, the end-effector site) are rewritten here at full double precision so that the
    file reproduces the model exactly.
    """
    if isinstance(arm, Manipulator):
        arm = build(arm, options)
    elif not isinstance(arm, BuiltArm):
        raise InputError(f"arm: expected a mjcf.BuiltArm or a zrp.Manipulator, got "
                         f"{type(arm).__name__}")
    text = arm.spec.to_xml()
    root = parse_xml(text, label="the built arm's MJCF", error=MJCFOutputError)
    assert root is not None
    model = arm.manipulator
    pre = arm.options.prefix
    bodies_m = np.asarray(model.bodies) * arm.scale
    by_name = {el.get("name"): el for el in root.iter() if el.get("name")}
    for k in range(model.n):
        body = by_name[f"{pre}link{k + 1}"]
        body.set("pos", _fmt(bodies_m[k]))
        joint = by_name[f"{pre}{joint_name(model, k)}"]
        joint.set("axis", _fmt(model.axes[k]))
        if joint.get("range") is not None:  # joint limits, full precision as well
            s = arm.scale if model.prismatic[k] else 1.0
            joint.set("range", _fmt(np.asarray(model.joints[k].limits) * s))
    site = by_name[f"{pre}end_effector"]
    site.set("pos", _fmt(bodies_m[model.n]))
    site.set("quat", _fmt(hand_quat(model)))
    ET.indent(root, space="  ")
    comment = (f"<!-- {model.name}: built by zrp-accuracy mjcf from a zero-reference-position "
               f"model ({model.length_unit} -> m x {arm.scale:g}); qpos = 0 is the zero "
               f"reference. -->\n")
    return comment + ET.tostring(root, encoding="unicode") + "\n"


def _cannot_write(path: str | os.PathLike[str], exc: Exception) -> MJCFOutputError:
    why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
    return MJCFOutputError(f"output {str(path)!r}: cannot write ({why})")


def save_mjcf(arm: BuiltArm | Manipulator, path: str | os.PathLike[str], *,
              overwrite: bool = False, options: MJCFOptions | None = None) -> Path:
    """Write :func:`mjcf_xml` to ``path`` atomically; refuses to replace a file unless
    ``overwrite`` (checked before the model is built).

    Raises:
        zrp.OutputExistsError: ``path`` exists and ``overwrite`` is False.
        mjcf.MJCFOutputError: the file cannot be written there.
    """
    try:
        (target,) = check_writable([path], overwrite)
    except InputError as exc:  # a folder, or a path under a file
        raise _cannot_write(path, exc) from exc
    text = mjcf_xml(arm, options)
    try:
        return write_text(target, text, overwrite=overwrite)
    except InputError as exc:  # the folder cannot be created or written
        raise _cannot_write(path, exc) from exc
