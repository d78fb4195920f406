"""The files a model names, checked before MuJoCo opens them.

MuJoCo reads an MJCF's meshes, textures, height fields, skins and ``<include>`` files (and a
URDF's meshes) itself, with no limit and no check of the kind of file: a mesh that is a FIFO
hangs the reader forever, a device or a 10 GB file is read. :func:`check_model_files` walks the
model's XML first (``<include>`` files too, at most :data:`MAX_INCLUDE_DEPTH` deep) and refuses,
by attribute and path, every referenced file that exists but is not a regular file, or is
larger than :data:`MAX_ASSET_BYTES`. A file that does not exist is left to MuJoCo, whose
message names it. Every loader of the layer calls it (:func:`mjcf.load_shipped`,
:func:`mjcf.load_shipped_spec`, :func:`mjcf.importer.load_mujoco_model`).

A name is looked up where MuJoCo may look: beside the model file and under the compiler's
``meshdir``, ``texturedir`` and ``assetdir``; each place where it exists is checked.
"""

from __future__ import annotations

import os
import stat
import xml.etree.ElementTree as ET
from pathlib import Path

from mjcf.errors import MJCFImportError
from zrp.textio import read_text
from zrp.xmlio import parse_xml

__all__ = ["MAX_ASSET_BYTES", "MAX_INCLUDE_DEPTH", "check_asset_file", "check_model_files"]

#: Largest file a model may name (a mesh of some million triangles is well below).
MAX_ASSET_BYTES = 512 * 2**20
#: Deepest chain of ``<include>`` files followed.
MAX_INCLUDE_DEPTH = 8
#: attributes that name a file (MJCF mesh/hfield/skin/include/model/texture, URDF mesh)
_FILE_ATTRS = ("file", "filename", "fileright", "fileleft", "fileup", "filedown", "filefront",
               "fileback")
_DIR_ATTRS = ("meshdir", "texturedir", "assetdir")


def _kind(mode: int) -> str:
    for test, kind in ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a device"),
                       (stat.S_ISBLK, "a device"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISDIR, "a folder")):
        if test(mode):
            return kind
    return "not a regular file"


def check_asset_file(p: Path, what: str, max_bytes: int = MAX_ASSET_BYTES) -> bool:
    """True when ``p`` is a regular file within the size; False when missing; else a
    :class:`~mjcf.errors.MJCFImportError` naming ``what`` and the path."""
    try:
        st = os.stat(p)
    except (FileNotFoundError, NotADirectoryError):
        return False
    except OSError as exc:
        raise MJCFImportError(f"{what}: {str(p)!r} cannot be checked ({exc.strerror or exc})"
                              ) from None
    if not stat.S_ISREG(st.st_mode):
        raise MJCFImportError(f"{what}: {str(p)!r} is {_kind(st.st_mode)}, not a regular file; "
                              "MuJoCo would read it without end: refused before loading")
    if st.st_size > max_bytes:
        raise MJCFImportError(f"{what}: {str(p)!r} is {st.st_size / 2**20:.0f} MiB, more than "
                              f"the {max_bytes / 2**20:.0f} MiB a model's file may have")
    return True


def _parse(text: str, label: str) -> ET.Element | None:
    """The XML's root; None when it is not well-formed (MuJoCo refuses it then, by name,
    before it opens any file it names). More markup than :data:`zrp.xmlio.MAX_XML_MARKUP`
    is refused by name (it bounds MuJoCo's parse too)."""
    return parse_xml(text, label=label, error=MJCFImportError, strict=False)


def _dirs(root: ET.Element, base: Path) -> list[Path]:
    out = [base]
    for comp in root.iter("compiler"):
        for attr in _DIR_ATTRS:
            d = comp.get(attr)
            if d:
                out.append(Path(d) if Path(d).is_absolute() else base / d)
    return out


def _walk(root: ET.Element, base: Path, dirs: list[Path], label: str, depth: int,
          max_bytes: int) -> None:
    for el in root.iter():
        for attr in _FILE_ATTRS:
            name = el.get(attr)
            if not name or name.startswith("package://"):
                continue  # package:// is resolved (and checked) by mjcf.shipped
            name = name[len("file://"):] if name.startswith("file://") else name
            what = f"{label}: <{el.tag} {attr}=...>"
            rel = Path(name)
            places = [rel] if rel.is_absolute() else [d / rel for d in dirs]
            found = [p for p in dict.fromkeys(places) if check_asset_file(p, what, max_bytes)]
            if el.tag == "include" and found:
                if depth >= MAX_INCLUDE_DEPTH:
                    raise MJCFImportError(f"{what}: more than {MAX_INCLUDE_DEPTH} nested "
                                          "<include> files")
                inc = found[0]
                sub = _parse(read_text(inc, label=str(inc), error=MJCFImportError), str(inc))
                if sub is not None:
                    _walk(sub, base, dirs, str(inc), depth + 1, max_bytes)


def check_model_files(path: str | os.PathLike[str] | None, *, text: str | None = None,
                      max_bytes: int = MAX_ASSET_BYTES) -> None:
    """Check the model file ``path`` (or the XML ``text``, its names relative to ``path``'s
    folder, or to the working folder when ``path`` is None) and every file it names.

    Raises:
        MJCFImportError: a file named is not a regular file or is too large (the message
            names the element, the attribute and the path).
    """
    base = Path.cwd() if path is None else Path(path).parent
    label = "source XML" if path is None else f"source {str(path)!r}"
    if text is None:
        if path is None:
            raise MJCFImportError("source: give a model file or its XML text")
        text = read_text(path, label=label, error=MJCFImportError)
    root = _parse(text, label)
    if root is not None:
        _walk(root, base, _dirs(root, base), label, 0, max_bytes)
