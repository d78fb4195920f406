"""Standard output that cannot be written: closed early (``zrp measure ... | head -1``), the
command ends quietly; on a full or failing device (``zrp fk > /dev/full``), one line.

Python ignores SIGPIPE, so writing to a pipe whose reader has gone raises
``BrokenPipeError``, and the interpreter's final flush of ``sys.stdout`` raises it again
("Exception ignored ..."). Python's documented recipe
(https://docs.python.org/3/library/signal.html#note-on-sigpipe): catch it, point the closed
stream at ``os.devnull`` so nothing is flushed into the closed pipe at exit, and end with an
error status; here 128 + SIGPIPE (141), what a shell reports for a program that SIGPIPE ended,
as ``main`` returns 130 (128 + SIGINT) for Ctrl-C.

Only a closed standard stream ends a command this way: a broken pipe elsewhere (a subprocess,
a cluster's connection) is not the reader going away and is raised as before.

A full disk, a quota or an I/O error is the device's, not the command's: a file a command
writes names it already (``zrp.output``: "cannot write (No space left on device)"); the same
error on standard output is one line too (:func:`device_error`), not a traceback.
"""

from __future__ import annotations

import errno
import os
import select
import signal
import sys
from typing import TextIO

__all__ = ["CLOSED_EXIT", "DEVICE_ERRORS", "PATH_ERRORS", "closed_output", "device_error",
           "path_error"]

#: The exit status of a command whose output was closed early (128 + SIGPIPE, as a shell shows
#: a program that SIGPIPE ended; 141 on Linux and macOS).
CLOSED_EXIT = 128 + int(getattr(signal, "SIGPIPE", 13))


#: The errors of a device or file system (no space, quota, file too large, I/O): the
#: environment's, said in one line, never a sign of a bug in the command.
DEVICE_ERRORS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})
#: Errors of a file name the user gave (too long, not allowed, a file where a folder must be):
#: one line naming the file, as any other bad input.
PATH_ERRORS = frozenset({errno.ENAMETOOLONG, errno.EACCES, errno.EPERM, errno.EROFS,
                         errno.ENOTDIR, errno.EISDIR, errno.ELOOP})


def device_error(exc: OSError) -> str | None:
    """The one-line message of ``exc`` when it is one of :data:`DEVICE_ERRORS` (``zrp fk >
    /dev/full``), else None (raised as before: a traceback shows where it came from). What
    could not be written is discarded (pointing stdout at ``os.devnull`` if its buffer still
    holds it), so the interpreter's final flush does not fail again."""
    if exc.errno not in DEVICE_ERRORS:
        return None
    fd = _fd(sys.stdout)
    try:
        if sys.stdout is not None:
            sys.stdout.flush()
    except OSError:
        if fd is not None:
            _to_devnull(fd)
    why = exc.strerror or str(exc)
    return (f"{exc.filename}: cannot write ({why})" if exc.filename
            else f"cannot write the output ({why})")


def path_error(exc: OSError) -> str | None:
    """The one-line message of ``exc`` when it is one of :data:`PATH_ERRORS` and names its
    file (shortened to 120 characters), else None."""
    if exc.errno not in PATH_ERRORS or not exc.filename:
        return None
    name = str(exc.filename)
    name = name if len(name) <= 120 else name[:117] + "..."
    return f"{name}: {exc.strerror or exc}"


def _to_devnull(fd: int) -> None:
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _fd(stream: TextIO | None) -> int | None:
    try:
        return None if stream is None else stream.fileno()
    except (AttributeError, OSError, ValueError):  # replaced by a caller (io.StringIO, capsys)
        return None


def _reader_gone(fd: int) -> bool | None:
    """True when ``fd`` is a pipe or socket whose reader has closed it, False when it is
    open, None where this cannot be told (no ``select.poll``, as on Windows)."""
    if not hasattr(select, "poll"):
        return None
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poller.poll(0))


def closed_output() -> bool:
    """After a ``BrokenPipeError``: whether it was the command's stdout or stderr whose reader
    went away. Each such stream's descriptor is then pointed at ``os.devnull`` (the recipe),
    so the interpreter's final flush does not fail again. False for a broken pipe elsewhere,
    and for streams a caller replaced (``io.StringIO``): the caller's error to see."""
    closed = False
    for stream in (sys.stdout, sys.stderr):
        fd = _fd(stream)
        if fd is None:
            continue
        gone = _reader_gone(fd)
        if gone is None and stream is not sys.stdout:
            continue  # cannot tell: assume it was stdout, the recipe's case
        if gone is None or gone:
            _to_devnull(fd)
            closed = True
    return closed
