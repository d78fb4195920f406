"""One way for the command line to change how a signal is handled for a while."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["handling"]


@contextlib.contextmanager
def handling(signum: int, handler: Callable[[int, Any], Any] | int) -> Iterator[None]:
    """Handle ``signum`` with ``handler`` (a function or ``signal.SIG_IGN``) inside the block,
    then restore the previous handler. Python changes handlers only from the main thread;
    elsewhere (a command run from a test's thread, a notebook's worker) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signum, handler)
    try:
        yield
    finally:
        signal.signal(signum, previous)
