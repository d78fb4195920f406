"""Load an arm's URDF or MJCF into MuJoCo as it was shipped: its inertials, joint limits,
damping and friction kept; mesh references resolved or dropped.

A URDF from a ROS package names its meshes ``package://PKG/rel/path``; MuJoCo reads that as a
relative file name and fails (``Error opening file 'package:/...'``). :func:`load_shipped`
resolves each mesh against the file's own package tree (the first folder above the file that
is named PKG, or that holds a folder PKG), and drops the ``<visual>`` or ``<collision>``
element of a mesh it cannot resolve or MuJoCo cannot read (Collada ``.dae``): geometry is not
needed for the dynamics, the ``<inertial>`` elements are. The URDF is compiled with
``fusestatic="false"`` (links on fixed joints stay bodies, under their own names),
``discardvisual="false"`` and ``inertiafromgeom="false"`` (a link without ``<inertial>`` has
no mass: nothing is invented from its meshes). ``<dynamics damping= friction=>`` become
MuJoCo joint ``damping`` and ``frictionloss`` (MuJoCo's URDF reader). An MJCF is compiled as
it is (its ``meshdir`` is relative to the file).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco

from mjcf.assets import check_asset_file, check_model_files
from mjcf.errors import MJCFImportError
from zrp.errors import InputError
from zrp.textio import read_text
from zrp.xmlio import read_xml

__all__ = ["MESH_SUFFIXES", "example_robot_data_root", "load_shipped", "load_shipped_spec",
           "resolve_mesh", "shipped_urdf_xml"]

#: Mesh file types MuJoCo reads; others (Collada .dae, ...) are dropped from a URDF.
MESH_SUFFIXES = (".stl", ".obj", ".msh")
_COMPILER = {"fusestatic": "false", "discardvisual": "false", "inertiafromgeom": "false",
             "balanceinertia": "false"}


def example_robot_data_root() -> Path | None:
    """example-robot-data's ``robots`` folder (its wheel installs it in Pinocchio's prefix,
    ``share/example-robot-data/robots``), or None without Pinocchio or the package."""
    try:
        import pinocchio
    except ImportError:
        return None
    base = Path(pinocchio.__file__).parent
    for up in (4, 3):
        root = base.parents[up - 1] / "share" / "example-robot-data" / "robots"
        if root.is_dir():
            return root
    return None


def resolve_mesh(uri: str, urdf_dir: Path) -> Path | None:
    """The file a URDF mesh ``filename`` names, or None when it is not found.

    ``package://PKG/rel``: ``A/rel`` for the first folder A above ``urdf_dir`` (itself
    included) named PKG, or ``A/PKG/rel`` for the first A holding a folder PKG;
    ``file://abs`` and plain paths (relative to ``urdf_dir``) as they are. A path that
    exists but is no regular file (a FIFO) is returned: :func:`shipped_urdf_xml` refuses it.
    """
    if uri.startswith("package://"):
        pkg, _, rel = uri[len("package://"):].partition("/")
        for a in (urdf_dir, *urdf_dir.parents):
            for cand in ((a / rel) if a.name == pkg else None, a / pkg / rel):
                if cand is not None and cand.exists():
                    return cand.resolve()
        return None
    path = Path(uri[len("file://"):] if uri.startswith("file://") else uri)
    path = path if path.is_absolute() else urdf_dir / path
    return path.resolve() if path.exists() else None


def shipped_urdf_xml(path: str | os.PathLike[str]) -> tuple[str, list[str]]:
    """The URDF text MuJoCo can compile: meshes resolved to absolute paths, the ``<visual>``
    / ``<collision>`` of unresolvable or unreadable meshes dropped, MuJoCo's compiler
    settings (module docstring) added. Returns (text, the mesh URIs dropped)."""
    p = Path(path)
    root = read_xml(p, label=f"source {str(p)!r}", error=MJCFImportError)  # bounded, linear
    if root.tag != "robot":
        raise MJCFImportError(f"source {str(p)!r}: the root element is <{root.tag}>, not "
                              "<robot>; not a URDF")
    dropped: list[str] = []
    for link in root.iter("link"):
        for kind in ("visual", "collision"):
            for el in list(link.findall(kind)):
                mesh = el.find("geometry/mesh")
                if mesh is None:
                    continue
                uri = mesh.get("filename", "")
                file = resolve_mesh(uri, p.parent)
                if file is not None:  # a regular file of bounded size, or refused by name
                    check_asset_file(file, f"source {str(p)!r}: mesh {uri!r}")
                if file is None or file.suffix.lower() not in MESH_SUFFIXES:
                    link.remove(el)
                    dropped.append(uri)
                else:
                    mesh.set("filename", str(file))
    for old in root.findall("mujoco"):
        root.remove(old)
    ext = ET.SubElement(root, "mujoco")
    ET.SubElement(ext, "compiler", _COMPILER)
    return ET.tostring(root, encoding="unicode"), dropped


def _shipped_file(path: str | os.PathLike[str]) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a .urdf or MJCF .xml file name, got "
                         f"{type(path).__name__}")
    p = Path(path)
    if not p.exists():
        raise MJCFImportError(f"source: no such file {str(p)!r} (expected a .urdf or an MJCF "
                              ".xml)")
    if p.suffix.lower() != ".urdf":  # a URDF's meshes are resolved and checked in
        check_model_files(p)         # shipped_urdf_xml
    else:
        read_text(p, label=f"source {str(p)!r}", error=MJCFImportError)  # a regular file
    return p


def load_shipped(path: str | os.PathLike[str]) -> mujoco.MjModel:
    """Compile an arm's shipped ``.urdf`` or MJCF ``.xml`` into MuJoCo (module docstring).

    Raises:
        MJCFImportError: no such file, not URDF/MJCF, or MuJoCo refuses it (its message
            kept, e.g. an inertia that violates the triangle inequality).
    """
    p = _shipped_file(path)
    try:
        if p.suffix.lower() == ".urdf":
            text, _ = shipped_urdf_xml(p)
            return mujoco.MjModel.from_xml_string(text)
        return mujoco.MjModel.from_xml_path(str(p))
    except ValueError as exc:
        raise MJCFImportError(f"source {str(p)!r}: MuJoCo could not compile it: {exc}"
                              ) from exc


def load_shipped_spec(path: str | os.PathLike[str]) -> mujoco.MjSpec:
    """The editable :class:`mujoco.MjSpec` of an arm's shipped ``.urdf`` or MJCF ``.xml``,
    read as :func:`load_shipped` reads it (``spec.compile()`` gives the same model), for a
    caller that edits the model and writes it out: an MJCF's ``meshdir`` is made absolute
    (a URDF's meshes already are), so the written copy loads from any folder.

    Raises:
        MJCFImportError: as :func:`load_shipped` (MuJoCo's parse errors here; its compile
            errors come from ``spec.compile()``).
    """
    p = _shipped_file(path)
    try:
        if p.suffix.lower() == ".urdf":
            return mujoco.MjSpec.from_string(shipped_urdf_xml(p)[0])
        spec = mujoco.MjSpec.from_file(str(p))
    except ValueError as exc:
        raise MJCFImportError(f"source {str(p)!r}: MuJoCo could not read it: {exc}") from exc
    spec.meshdir = str((p.parent / (spec.meshdir or "")).resolve())
    return spec
