"""The joints a model file names, for matching a log's joints by name (issue 44): every joint
of an MJCF or URDF (the arm's chain and those off it: fingers, a head, wheels), and the link
that ends the chain of a chosen set of joints (``--joints``, handed to
:func:`mjcf.arm.load_arm` as its ``end_link``). Kept apart from :mod:`mjcf.arm` (which loads
the arm) so that each changes on its own."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from mjcf.errors import MJCFImportError
from mjcf.shipped import load_shipped_spec
from zrp.errors import InputError

__all__ = ["chain_end", "is_model_file", "model_joints"]


def is_model_file(model: str) -> bool:
    """An MJCF or URDF file (else a ZRP model name or .toml)."""
    return Path(model).suffix.lower() in (".xml", ".urdf", ".mjcf")


def _bodies(model: str) -> dict[str, str]:
    """Joint name -> its body (link), in the model's order."""
    path = Path(model)
    if not path.is_file():
        raise InputError(f"model: no such file {str(path)!r} (an MJCF .xml or a URDF)")
    try:
        spec = load_shipped_spec(path)
    except MJCFImportError as exc:
        raise InputError(f"model {path.name}: cannot load: {exc}") from exc
    return {j.name: j.parent.name for j in spec.joints if j.name}


def model_joints(model: str) -> tuple[str, ...]:
    """Every named joint of the MJCF or URDF ``model``, in its order (() for a ZRP model)."""
    return tuple(_bodies(model)) if is_model_file(model) else ()


def chain_end(model: str, joints: Sequence[str], option: str = "--joints") -> str:
    """The body (link) of the last of ``joints`` in the model's order: the arm's last link
    when ``joints`` are its chain; a name the model lacks is refused by name."""
    if not is_model_file(model):
        raise InputError(f"{option}: for an MJCF or URDF model (a ZRP model's joints are its "
                         "whole chain)")
    bodies = _bodies(model)
    unknown = [j for j in joints if j not in bodies]
    if unknown:
        raise InputError(f"{option}: the model has no joint {', '.join(unknown)} (its joints: "
                         f"{', '.join(bodies)})")
    last = max(joints, key=list(bodies).index)
    return bodies[last]
