"""Names of default outputs (part of :mod:`zrp.output`): :func:`safe_name`, the one function
that turns an input's name (a log's stem, a model's file name, a robot's data file) into a
file or folder name a command may write under its default folder, and :func:`check_no_links`,
which refuses a symbolic link on the way from an output folder down to a folder inside it."""

from __future__ import annotations

import os
import re
from pathlib import Path

from zrp.errors import OutputKindError

__all__ = ["NAME_MAX_CHARS", "check_no_links", "safe_name"]

#: Longest name :func:`safe_name` returns (characters; ASCII, so bytes too).
NAME_MAX_CHARS = 100
_UNSAFE = re.compile(r"[^A-Za-z0-9_-]+")


def safe_name(text: object, *, default: str = "model", lower: bool = False) -> str:
    """``text`` as a plain name: every run of characters other than ASCII letters, digits,
    ``_`` and ``-`` becomes one ``_`` (so no ``/``, ``\\``, ``..``, dot, control character or
    space survives), ``_`` and ``-`` trimmed at both ends (no name reads as an option), at most
    :data:`NAME_MAX_CHARS` characters; ``default`` when nothing is left. ``lower``: in lower
    case."""
    name = _UNSAFE.sub("_", str(text)).strip("_-")[:NAME_MAX_CHARS].rstrip("_-")
    name = name or default
    return name.lower() if lower else name


def check_no_links(root: str | os.PathLike[str], folder: str | os.PathLike[str]) -> Path:
    """Refuse a symbolic link at ``root`` or at any existing folder between ``root`` and
    ``folder`` (``folder`` inside ``root``), so that a run never writes through a link into
    another folder; returns ``folder`` as a :class:`~pathlib.Path`.

    Raises:
        OutputKindError: naming the link and its target.
    """
    root_p, p = Path(root), Path(folder)
    chain = [p, *[q for q in p.parents if root_p == q or root_p in q.parents]]
    for q in chain:
        if q.is_symlink():
            raise OutputKindError(f"{q}: is a symbolic link (to {os.readlink(q)}); an output "
                                  "folder is written only as a real folder, never through a "
                                  "link, even with --force or --resume: remove the link")
    return p
