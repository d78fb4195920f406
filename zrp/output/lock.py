"""The lock of an output folder (part of :mod:`zrp.output`): a folder belongs to one run at a
time. :func:`acquire` creates the lock file :data:`LOCK_NAME` with ``O_EXCL`` and writes
"pid host" in it; a second run waits at most ``wait_s`` seconds (:data:`LOCK_WAIT_S`), then
is refused with :class:`~zrp.errors.OutputBusyError` naming the lock file and the holder's
process. A lock left by a process that no longer runs (on this host) is taken over."""

from __future__ import annotations

import contextlib
import os
import socket
import stat
import time
from pathlib import Path

from zrp.errors import InputError, OutputBusyError, OutputKindError

__all__ = ["LOCK_NAME", "LOCK_WAIT_S", "acquire", "pid_alive", "release"]

#: Name of the lock file an :class:`~zrp.output.OutputDir` holds while a run writes into it.
LOCK_NAME = ".zrp-output.lock"
#: Longest wait for another run's lock on an output folder before :class:`OutputBusyError`.
LOCK_WAIT_S = 3.0


def pid_alive(pid: int) -> bool:
    """Does process ``pid`` run on this host?"""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:
        return False
    return True


def _holder(lock: Path) -> tuple[int, str]:
    """(pid, host) written in the lock file; (0, "") when it is gone, (-1, "") when
    unreadable. Read without following a link or blocking on a FIFO, at most 256 bytes."""
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


def acquire(root: Path, wait_s: float = LOCK_WAIT_S) -> Path:
    """Take the lock of the (existing) folder ``root``; returns the lock file's path.

    Raises:
        OutputBusyError: another live run holds it after ``wait_s`` seconds, or a stale lock
            could not be taken over.
        InputError: the folder cannot be written.
    """
    lock = root / LOCK_NAME
    me = f"{os.getpid()} {socket.gethostname()}\n"
    t0 = time.monotonic()
    stale = 0
    while True:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            pid, host = _holder(lock)
            if pid > 0 and (host != socket.gethostname() or pid_alive(pid)):
                waited = time.monotonic() - t0
                if waited >= wait_s:
                    raise OutputBusyError(root, pid, host, lock, waited) from None
                time.sleep(min(0.2, wait_s))
                continue
            stale += 1
            if stale > 3:
                raise OutputBusyError(root, -1, "", lock) from None
            with contextlib.suppress(OSError):  # stale: its process has ended
                lock.unlink()
            continue
        except OSError as exc:
            raise InputError(f"{root}: cannot write into the folder "
                             f"({exc.strerror or exc})") from exc
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(me)
        return lock


def release(lock: Path) -> None:
    """Remove the lock file (already gone: nothing to do)."""
    with contextlib.suppress(OSError):
        lock.unlink()
