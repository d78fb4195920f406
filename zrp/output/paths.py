"""Which paths an output may take: the name checks, the file-kind checks (only regular files
are replaced: never a symbolic link, a device, a FIFO, a socket or a folder) and the
refusal to replace an existing file without ``overwrite`` (part of :mod:`zrp.output`)."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path

from zrp.errors import InputError, OutputExistsError, OutputKindError
from zrp.output.inputs import check_not_input

__all__ = ["NAME_MAX_BYTES", "as_path", "check_regular", "check_writable", "make_folder"]

#: Longest file or folder name (one path component, UTF-8 bytes) on common file systems
#: (ext4, XFS, APFS, NTFS): a longer one is refused by name before anything is written.
NAME_MAX_BYTES = 255
_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a folder"))


def as_path(path: str | os.PathLike[str], field: str) -> Path:
    """``path`` as a :class:`~pathlib.Path`, refusing a non-path, an empty string or a name
    component longer than :data:`NAME_MAX_BYTES` (the message names ``field``)."""
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)):
        raise InputError(f"{field}: expected a file or folder path, got {type(path).__name__}")
    p = Path(path)
    if not str(p).strip():
        raise InputError(f"{field}: expected a file or folder path, got an empty string")
    for part in p.parts:
        n = len(os.fsencode(part))
        if n > NAME_MAX_BYTES:
            raise InputError(f"{field}: name too long ({n} bytes; file systems allow "
                             f"{NAME_MAX_BYTES} a name): {part[:40]}...")
    return p


def _lstat(p: Path) -> os.stat_result | None:
    """``os.lstat`` of ``p`` (None when missing); other failures are named errors."""
    try:
        return os.lstat(p)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        raise InputError(f"{p}: cannot check the path ({exc.strerror or exc})") from exc


def check_regular(p: Path) -> bool:
    """True when ``p`` exists as a regular file, False when missing.

    Raises:
        OutputKindError: ``p`` is a symbolic link or a special file (device, FIFO, socket),
            which no writer replaces, even with ``overwrite=True``.
    """
    st = _lstat(p)
    if st is None:
        return False
    if stat.S_ISLNK(st.st_mode):
        try:
            target = os.readlink(p)
        except OSError:
            target = "?"
        raise OutputKindError(f"{p}: is a symbolic link (to {target}); an output is written "
                              "only as a regular file, never through or over a link, even with "
                              "--force: remove the link or choose another name")
    for test, kind in _KINDS:
        if test(st.st_mode):
            raise OutputKindError(f"{p}: is {kind}, not a regular file; outputs replace only "
                                  "regular files, even with --force: choose another name")
    return True


def check_writable(paths: Iterable[str | os.PathLike[str]], overwrite: bool) -> list[Path]:
    """Check that every path may be written: refuse existing files unless ``overwrite``.

    Returns:
        the paths as :class:`~pathlib.Path`.

    Raises:
        OutputExistsError: naming every path that exists (and ``overwrite`` is False).
        InputError: a path names an existing folder, or lies under an existing file.
    """
    out = [as_path(p, "path") for p in paths]
    existing = []
    for p in out:
        st = _lstat(p)
        if st is not None and stat.S_ISDIR(st.st_mode):
            raise InputError(f"{p}: is a folder; expected a file name to write")
        for parent in p.parents:
            try:
                bad = parent.exists() and not parent.is_dir()
            except OSError as exc:
                raise InputError(f"{p}: cannot check the path ({exc.strerror or exc})") from exc
            if bad:
                raise InputError(f"{p}: cannot write under {parent}, which is a file, not a "
                                 "folder")
        if check_regular(p):
            check_not_input(p)
            existing.append(p)
    if existing and not overwrite:
        raise OutputExistsError(existing)
    return out


def make_folder(folder: Path) -> None:
    """Create ``folder`` with its parents (nothing when it exists); a file in the way, or a
    folder that cannot be created, is a named :class:`~zrp.errors.InputError`."""
    for parent in folder.parents:
        if parent.exists() and not parent.is_dir():
            raise InputError(f"{folder}: cannot create the folder: {parent} is a file, not a "
                             "folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError as exc:
        raise InputError(f"{folder}: exists and is not a folder") from exc
    except OSError as exc:
        raise InputError(f"{folder}: cannot create the folder ({exc.strerror or exc})") from exc
