"""The output-writing policy: one helper that every writer in every layer uses.

* Nothing the user has is replaced without ``overwrite=True`` (``--force`` on the command
  line): :func:`check_writable` refuses, naming every file that exists, before any work is done.
* Each file appears whole or not at all: it is written under a temporary name in the same
  folder and moved into place with :func:`os.replace` (atomic on POSIX and Windows), so an
  interrupted run never leaves half a CSV behind.
* Only regular files are replaced: a symbolic link, a device, a FIFO or a socket at an output
  path is refused with :class:`~zrp.errors.OutputKindError`, even with ``overwrite=True`` (as
  root, ``--out /dev/null --force`` would otherwise replace the system's). An output folder
  that is itself a symbolic link is refused, not resolved (the message names its target, to
  pass instead), so a run never writes through a link into another folder.
* A name longer than the file system allows (255 bytes a component) is refused by name.
* An output folder belongs to one run at a time: :class:`OutputDir` holds a lock file
  (``.zrp-output.lock``, created with ``O_EXCL``) while it writes, so two concurrent runs into
  one folder never mix their files; the second waits at most ``lock_wait_s`` seconds
  (:data:`LOCK_WAIT_S`), then is refused with :class:`OutputBusyError` naming the lock file and
  the holder's process. A lock left by a process that no longer runs is taken over.
* A writer that declares the files it owns (``names``) with ``prune=True`` removes, on a clean
  exit, those of them an earlier run left and this run did not write (the plots of a run
  before ``--no-plots``), so no stale file is left beside (or linked from) the new results.

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
import stat
import time
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from zrp.errors import InputError, OutputBusyError, OutputExistsError, OutputKindError

__all__ = [
    "GENERATED_MARK",
    "LOCK_NAME",
    "LOCK_WAIT_S",
    "NAME_MAX_BYTES",
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
#: Longest wait for another run's lock on an output folder before :class:`OutputBusyError`.
LOCK_WAIT_S = 3.0
#: Longest file or folder name (one path component, UTF-8 bytes) on common file systems
#: (ext4, XFS, APFS, NTFS): a longer one is refused by name before anything is written.
NAME_MAX_BYTES = 255
#: Longest suffix the temporary file keeps (so writers that infer the format from it can).
_SUFFIX_MAX = 16
_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a folder"))


def _as_path(path: str | os.PathLike[str], field: str) -> Path:
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
    out = [_as_path(p, "path") for p in paths]
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
            existing.append(p)
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
    suffix = p.suffix if len(p.suffix) <= _SUFFIX_MAX else ""
    tmp = p.with_name(f".zrp-{os.getpid()}-{time.monotonic_ns()}.tmp{suffix}")
    try:
        yield tmp
        if not tmp.exists():
            raise InputError(f"{p}: the writer produced no file")
        # checked again: a link or a device may have appeared while we were writing
        if check_regular(p) and not overwrite:
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
    from zrp.jsonio import dumps  # NumPy: on use, so that `zrp --help` does not load it

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
                 names: Sequence[str] = (), prune: bool = False,
                 lock_wait_s: float = LOCK_WAIT_S) -> None:
        self.root = _as_path(path, "out_dir")
        self.overwrite = bool(overwrite)
        self.names = tuple(names)
        self.prune = bool(prune)
        self.lock_wait_s = float(lock_wait_s)
        self.written: list[Path] = []
        #: files of an earlier run removed on exit (``prune``): declared, not written now
        self.removed: list[Path] = []
        self._lock: Path | None = None

    # ---- the lock --------------------------------------------------------------------------
    def _holder(self, lock: Path) -> tuple[int, str]:
        """(pid, host) written in the lock file; (-1, "") when unreadable. Read without
        following a link or blocking on a FIFO, at most 256 bytes."""
        try:
            fd = os.open(lock, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
        except FileNotFoundError:
            return 0, ""
        except OSError as exc:
            raise OutputKindError(f"{lock}: the output folder's lock file cannot be read "
                                  f"({exc.strerror or exc}); remove it if no run is writing "
                                  "into the folder") from exc
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                raise OutputKindError(f"{lock}: the output folder's lock is not a regular "
                                      "file; remove it if no run is writing into the folder")
            text = os.read(fd, 256).decode("utf-8", "replace")
        finally:
            os.close(fd)
        pid_s, _, host = text.strip().partition(" ")
        try:
            return int(pid_s), host
        except ValueError:
            return -1, ""

    def _acquire(self) -> None:
        lock = self.root / LOCK_NAME
        me = f"{os.getpid()} {socket.gethostname()}\n"
        t0 = time.monotonic()
        pid, host, stale = -1, "", 0
        while True:
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid, host = self._holder(lock)
                if pid > 0 and (host != socket.gethostname() or _pid_alive(pid)):
                    waited = time.monotonic() - t0
                    if waited >= self.lock_wait_s:
                        raise OutputBusyError(self.root, pid, host, lock, waited) from None
                    time.sleep(min(0.2, self.lock_wait_s))
                    continue
                stale += 1
                if stale > 3:
                    raise OutputBusyError(self.root, -1, "", lock) from None
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

    def __enter__(self) -> OutputDir:
        if self.root.is_symlink():
            raise OutputKindError(f"{self.root}: the output folder is a symbolic link (to "
                                  f"{os.readlink(self.root)}); refused, not resolved: pass the "
                                  f"real folder ({self.root.resolve()}) to write there")
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

    def __exit__(self, exc_type: object, *exc: object) -> None:
        try:
            if exc_type is None and self.prune and self._lock is not None:
                self._prune()
        finally:
            self._release()

    def _prune(self) -> None:
        """Remove the declared files this run did not write (left by an earlier run)."""
        mine = set(self.written)
        for name in self.names:
            p = self.root / name
            if p not in mine and check_regular(p):
                try:
                    p.unlink()
                except OSError as exc:
                    raise InputError(f"{p}: an earlier run's output that this run does not "
                                     f"make cannot be removed ({exc.strerror or exc})") from exc
                self.removed.append(p)

    # ---- writing ---------------------------------------------------------------------------
    def _target(self, name: str) -> Path:
        if self._lock is None:
            raise InputError(f"{self.root}: write inside `with OutputDir(...)`")
        p = self.root / name
        if Path(name).is_absolute() or ".." in Path(name).parts:
            raise InputError(f"{name!r}: expected a file name inside {self.root}")
        for sub in list(p.parents)[: len(Path(name).parts) - 1]:  # folders inside the root
            if sub.is_symlink():
                raise OutputKindError(f"{sub}: is a symbolic link inside the output folder; "
                                      "refused, not resolved: remove it")
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
