"""The output-writing policy: one helper that every writer in every layer uses.

* Nothing the user has is replaced without ``overwrite=True`` (``--force`` on the command
  line): :func:`check_writable` refuses, naming every file that exists, before any work is done.
* Each file appears whole or not at all: it is written under a temporary name in the same
  folder and moved into place with :func:`os.replace` (atomic on POSIX and Windows), so an
  interrupted run never leaves half a CSV behind.
* An output folder belongs to one run at a time: :class:`OutputDir` holds a lock file
  (``.zrp-output.lock``, created with ``O_EXCL``) while it writes, so two concurrent runs into
  one folder never mix their files; the second is refused with :class:`OutputBusyError`
  naming the first one's process. A lock left by a process that no longer runs is taken over.

Typical use::

    with OutputDir("results", overwrite=False, names=("a.csv", "b.png")) as out:
        ...                                      # compute: the names were checked up front
        out.write_text("a.csv", text)
        with out.path("b.png") as tmp:           # for writers that want a file name
            fig.savefig(tmp)
    out.written                                  # the paths written, in order
"""

from __future__ import annotations

import contextlib
import os
import socket
import time
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from zrp.errors import InputError, OutputBusyError, OutputExistsError
from zrp.jsonio import dumps

__all__ = [
    "GENERATED_MARK",
    "LOCK_NAME",
    "OutputDir",
    "atomic_path",
    "check_writable",
    "claim_generated",
    "write_bytes",
    "write_json",
    "write_text",
]

#: Name of the lock file an :class:`OutputDir` holds while a run writes into it.
LOCK_NAME = ".zrp-output.lock"
#: Mark of a folder created for generated output (the commands' default folders, such as
#: ``renders/``): see :func:`claim_generated`.
GENERATED_MARK = ".zrp-generated"


def _as_path(path: str | os.PathLike[str], field: str) -> Path:
    if isinstance(path, (bytes, bytearray)) or not isinstance(path, (str, os.PathLike)):
        raise InputError(f"{field}: expected a file or folder path, got {type(path).__name__}")
    p = Path(path)
    if not str(p).strip():
        raise InputError(f"{field}: expected a file or folder path, got an empty string")
    return p


def check_writable(paths: Iterable[str | os.PathLike[str]], overwrite: bool) -> list[Path]:
    """Check that every path may be written: refuse existing files unless ``overwrite``.

    Returns:
        the paths as :class:`~pathlib.Path`.

    Raises:
        OutputExistsError: naming every path that exists (and ``overwrite`` is False).
        InputError: a path names an existing folder, or lies under an existing file.
    """
    out = [_as_path(p, "path") for p in paths]
    for p in out:
        if p.is_dir():
            raise InputError(f"{p}: is a folder; expected a file name to write")
        for parent in p.parents:
            if parent.exists() and not parent.is_dir():
                raise InputError(f"{p}: cannot write under {parent}, which is a file, not a "
                                 "folder")
    existing = [p for p in out if p.exists() or p.is_symlink()]
    if existing and not overwrite:
        raise OutputExistsError(existing)
    return out


def _mkdir(folder: Path) -> None:
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


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, overwrite: bool = False) -> Iterator[Path]:
    """A temporary file name beside ``path`` (same suffix, so writers can infer the format);
    on a clean exit it is moved onto ``path`` in one step, on an error it is removed.

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False.
        InputError: the folder cannot be created or written.
    """
    (p,) = check_writable([path], overwrite)
    _mkdir(p.parent)
    tmp = p.with_name(f".{p.stem}.{os.getpid()}-{time.monotonic_ns()}.tmp{p.suffix}")
    try:
        yield tmp
        if not tmp.exists():
            raise InputError(f"{p}: the writer produced no file")
        if not overwrite and p.exists():  # appeared while we were writing
            raise OutputExistsError([p])
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
    return write_text(path, dumps(obj, indent), overwrite=overwrite)


def claim_generated(folder: str | os.PathLike[str]) -> bool:
    """May files in ``folder`` be replaced as generated output, without ``overwrite``?

    True when the folder is missing or empty (it is created and marked now with
    :data:`GENERATED_MARK`) or carries the mark; False for a folder that holds files but not
    the mark, such as a ``renders/`` the user made in the working directory: its files are
    then replaced only with ``overwrite=True``. Commands call this for their default folders
    only.
    """
    root = _as_path(folder, "folder")
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
    _mkdir(root)
    write_text(root / GENERATED_MARK, "Generated output of zrp: files here are replaced by "
               "the next run of the command that wrote them.\n", overwrite=True)
    return True


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:
        return False
    return True


class OutputDir:
    """An output folder owned by this run while the ``with`` block lasts.

    Args:
        path: the folder (created with its parents when missing).
        overwrite: replace files that exist; without it an existing file is an error.
        names: the files this run will write, checked on entry so that a refusal comes
            before any work is done.
    """

    def __init__(self, path: str | os.PathLike[str], *, overwrite: bool = False,
                 names: Sequence[str] = ()) -> None:
        self.root = _as_path(path, "out_dir")
        self.overwrite = bool(overwrite)
        self.names = tuple(names)
        self.written: list[Path] = []
        self._lock: Path | None = None

    # ---- the lock --------------------------------------------------------------------------
    def _acquire(self) -> None:
        lock = self.root / LOCK_NAME
        me = f"{os.getpid()} {socket.gethostname()}\n"
        for _ in range(3):
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    pid_s, _, host = lock.read_text(encoding="utf-8").strip().partition(" ")
                    pid = int(pid_s)
                except (OSError, ValueError):
                    pid, host = -1, ""
                if pid > 0 and (host != socket.gethostname() or _pid_alive(pid)):
                    raise OutputBusyError(self.root, pid, host) from None
                with contextlib.suppress(OSError):  # stale: its process has ended
                    lock.unlink()
                continue
            except OSError as exc:
                raise InputError(f"{self.root}: cannot write into the folder "
                                 f"({exc.strerror or exc})") from exc
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                fh.write(me)
            self._lock = lock
            return
        raise OutputBusyError(self.root, -1, "")

    def __enter__(self) -> OutputDir:
        if self.root.exists() and not self.root.is_dir():
            raise InputError(f"{self.root}: exists and is not a folder; expected an output "
                             "folder")
        _mkdir(self.root)
        self._acquire()
        try:
            check_writable([self.root / n for n in self.names], self.overwrite)
        except BaseException:
            self._release()
            raise
        return self

    def _release(self) -> None:
        if self._lock is not None:
            with contextlib.suppress(OSError):
                self._lock.unlink()
            self._lock = None

    def __exit__(self, *exc: object) -> None:
        self._release()

    # ---- writing ---------------------------------------------------------------------------
    def _target(self, name: str) -> Path:
        if self._lock is None:
            raise InputError(f"{self.root}: write inside `with OutputDir(...)`")
        p = self.root / name
        if Path(name).is_absolute() or ".." in Path(name).parts:
            raise InputError(f"{name!r}: expected a file name inside {self.root}")
        return p

    @contextlib.contextmanager
    def path(self, name: str) -> Iterator[Path]:
        """A temporary path for ``name``, moved into place on a clean exit."""
        target = self._target(name)
        with atomic_path(target, overwrite=self.overwrite) as tmp:
            yield tmp
        self.written.append(target)

    def write_text(self, name: str, text: str) -> Path:
        p = write_text(self._target(name), text, overwrite=self.overwrite)
        self.written.append(p)
        return p

    def write_bytes(self, name: str, data: bytes) -> Path:
        p = write_bytes(self._target(name), data, overwrite=self.overwrite)
        self.written.append(p)
        return p

    def write_json(self, name: str, obj: Any, indent: int | None = 2) -> Path:
        p = write_json(self._target(name), obj, overwrite=self.overwrite, indent=indent)
        self.written.append(p)
        return p

    def savefig(self, name: str, fig: Any, **kwargs: Any) -> Path:
        """Save a Matplotlib figure as ``name`` (format from its suffix)."""
        with self.path(name) as tmp:
            fig.savefig(tmp, **kwargs)
        return self.root / name
