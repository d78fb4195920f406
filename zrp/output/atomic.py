"""Atomic writes (part of :mod:`zrp.output`): each file appears whole or not at all. It is
written under a temporary name in the same folder and moved into place with
:func:`os.replace` (atomic on POSIX and Windows), so an interrupted run never leaves half a
CSV behind; and :func:`claim_generated`, which marks a command's default folder as generated
output.

A process killed mid-write (``kill -9``, power loss) leaves its temporary file
(``.zrp-PID-N.tmp.SUFFIX``); :func:`clean_stale_temporaries` removes, at the next write into
the folder, those whose process no longer runs on this host or that are older than
:data:`STALE_AFTER_S` (a writer on another host of a shared folder), never anything else."""

from __future__ import annotations

import contextlib
import os
import re
import stat
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from zrp.errors import InputError, OutputExistsError
from zrp.output.inputs import check_not_input
from zrp.output.lock import pid_alive
from zrp.output.paths import as_path, check_regular, check_writable, make_folder

__all__ = ["GENERATED_MARK", "STALE_AFTER_S", "atomic_path", "claim_generated",
           "clean_stale_temporaries", "default_overwrite", "write_bytes", "write_json",
           "write_text"]

#: Mark of a folder created for generated output (the commands' default folders, such as
#: ``renders/``): see :func:`claim_generated`.
GENERATED_MARK = ".zrp-generated"
#: Longest suffix the temporary file keeps (so writers that infer the format from it can).
_SUFFIX_MAX = 16
#: A temporary file of the toolkit's own older than this is stale whatever its process.
STALE_AFTER_S = 24 * 3600.0
_TEMP_NAME = re.compile(r"\.zrp-(\d+)-\d+\.tmp(\.[^/\\]{1,15})?")


def clean_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files (``.zrp-PID-N.tmp[.SUFFIX]``, regular files only) that a
    writer killed mid-write left in ``folder``: its process has ended (on this host) or the
    file is older than :data:`STALE_AFTER_S`. Returns the files removed; an unreadable folder
    or a file that cannot be removed is left as it is."""
    removed: list[Path] = []
    now = time.time()
    try:
        entries = [e for e in os.scandir(folder) if e.name.startswith(".zrp-")]
    except OSError:
        return removed
    for e in entries:
        m = _TEMP_NAME.fullmatch(e.name)
        if m is None:
            continue
        try:
            st = e.stat(follow_symlinks=False)
            if not stat.S_ISREG(st.st_mode):
                continue
            if pid_alive(int(m.group(1))) and now - st.st_mtime < STALE_AFTER_S:
                continue
            os.unlink(e.path)
        except OSError:
            continue
        removed.append(Path(e.path))
    return removed


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, overwrite: bool = False,
                clean: bool = True) -> Iterator[Path]:
    """A temporary file name beside ``path`` (same suffix, so writers can infer the format);
    on a clean exit it is moved onto ``path`` in one step, on an error it is removed.
    ``clean``: first remove the stale temporaries of killed writers in the folder
    (:func:`clean_stale_temporaries`; an :class:`~zrp.output.OutputDir` does it once).

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
        InputError: the folder cannot be created or written.
    """
    (p,) = check_writable([path], overwrite)
    make_folder(p.parent)
    if clean:
        clean_stale_temporaries(p.parent)
    suffix = p.suffix if len(p.suffix) <= _SUFFIX_MAX else ""
    tmp = p.with_name(f".zrp-{os.getpid()}-{time.monotonic_ns()}.tmp{suffix}")
    try:
        yield tmp
        if not tmp.exists():
            raise InputError(f"{p}: the writer produced no file")
        # checked again: a link or a device may have appeared while we were writing
        if check_regular(p) and not overwrite:
            raise OutputExistsError([p])
        check_not_input(p)
        os.replace(tmp, p)
    except OSError as exc:
        if isinstance(exc, OutputExistsError):
            raise
        raise InputError(f"{p}: cannot write ({exc.strerror or exc})") from exc
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def write_text(path: str | os.PathLike[str], text: str, *, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8, ``\\n`` line ends) to ``path`` atomically; returns the path."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="\n")
    return Path(path)


def write_bytes(path: str | os.PathLike[str], data: bytes, *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_json(path: str | os.PathLike[str], obj: Any, *, overwrite: bool = False,
               indent: int | None = 2) -> Path:
    """Write ``obj`` as strict JSON (:func:`zrp.jsonio.dumps`: no NaN) atomically."""
    from zrp.jsonio import dumps  # NumPy: on use, so that `zrp --help` does not load it

    return write_text(path, dumps(obj, indent), overwrite=overwrite)


def default_overwrite(folder: str | os.PathLike[str], *, default: bool, force: bool,
                      page: str | None = None) -> bool:
    """May a command replace files in ``folder``: with ``force``, or when ``folder`` is the
    command's default folder and :func:`claim_generated` claims it. ``page``: a file in
    ``folder`` that will be written (the ``renders/`` index page), checked now, before any work.

    Raises:
        OutputExistsError: ``page`` exists and may not be replaced.
    """
    overwrite = force or (default and claim_generated(folder))
    if page is not None:
        check_writable([Path(folder) / page], overwrite)
    return overwrite


def claim_generated(folder: str | os.PathLike[str]) -> bool:
    """May files in ``folder`` be replaced as generated output, without ``overwrite``?

    True when the folder is missing or empty (it is created and marked now with
    :data:`GENERATED_MARK`) or carries the mark; False for a folder that holds files but not
    the mark, such as a ``renders/`` the user made in the working directory: its files are
    then replaced only with ``overwrite=True``. Commands call this for their default folders
    only.
    """
    root = as_path(folder, "folder")
    if root.is_dir():
        if (root / GENERATED_MARK).is_file():
            return True
        try:  # an empty folder (dot files aside) has nothing to lose: claimed
            if any(not p.name.startswith(".") for p in root.iterdir()):
                return False
        except OSError:
            return False
    elif root.exists():
        return False  # a file: OutputDir/check_writable say why it cannot be written
    make_folder(root)
    write_text(root / GENERATED_MARK, "Generated output of zrp: files here are replaced by "
               "the next run of the command that wrote them.\n", overwrite=True)
    return True
