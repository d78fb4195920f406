"""A command whose output is closed early (``zrp measure ... | head -1``) ends quietly.

Python ignores SIGPIPE, so writing to a pipe whose reader has gone raises
``BrokenPipeError``, and the interpreter's final flush of ``sys.stdout`` raises it again
("Exception ignored ..."). Python's documented recipe
(https://docs.python.org/3/library/signal.html#note-on-sigpipe): catch it, point the closed
stream at ``os.devnull`` so nothing is flushed into the closed pipe at exit, and end with an
error status; here 128 + SIGPIPE (141), what a shell reports for a program that SIGPIPE ended,
as ``main`` returns 130 (128 + SIGINT) for Ctrl-C.

Only a closed standard stream ends a command this way: a broken pipe elsewhere (a subprocess,
a cluster's connection) is not the reader going away and is raised as before.
"""

from __future__ import annotations

import os
import select
import signal
import sys
from typing import TextIO

__all__ = ["CLOSED_EXIT", "closed_output"]

#: The exit status of a command whose output was closed early (128 + SIGPIPE, as a shell shows
#: a program that SIGPIPE ended; 141 on Linux and macOS).
CLOSED_EXIT = 128 + int(getattr(signal, "SIGPIPE", 13))


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
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, fd)
            os.close(devnull)
            closed = True
    return closed
