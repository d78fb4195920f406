"""Progress of a long diagnosis: a tqdm bar on a terminal, periodic plain lines when stderr is
piped or redirected (a bar's carriage returns would pile up in a log file)."""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

__all__ = ["LINE_INTERVAL_S", "PeriodicLines", "progress_bar"]

#: seconds between two progress lines when stderr is not a terminal.
LINE_INTERVAL_S = 10.0


class PeriodicLines:
    """A minimal stand-in for a tqdm bar that prints ``desc: done/total (pct), elapsed`` at
    most every ``interval`` seconds, and a last line on :meth:`close` if it printed any."""

    def __init__(self, total: int, desc: str, stream: TextIO,
                 interval: float = LINE_INTERVAL_S) -> None:
        self.total, self.desc, self.stream, self.interval = max(total, 1), desc, stream, interval
        self.n = 0
        self.t0 = self.last = time.monotonic()
        self.printed = False

    def _line(self) -> None:
        el = time.monotonic() - self.t0
        self.stream.write(f"{self.desc}: {self.n}/{self.total} candidate fits "
                          f"({100 * self.n / self.total:.0f} %), {el:.0f} s\n")
        self.stream.flush()
        self.printed = True

    def update(self, k: int = 1) -> None:
        self.n += k
        now = time.monotonic()
        if now - self.last >= self.interval:
            self.last = now
            self._line()

    def close(self) -> None:
        if self.printed:
            self.n = self.total
            self._line()


def progress_bar(total: int, desc: str, enabled: bool, stream: TextIO | None = None) -> Any:
    """A tqdm bar (terminal), :class:`PeriodicLines` (pipe or file) or a disabled bar."""
    stream = sys.stderr if stream is None else stream
    # tqdm.auto probes for a notebook when imported: only when a bar is shown
    from tqdm.auto import tqdm

    if enabled and not stream.isatty():
        return PeriodicLines(total, desc, stream)
    return tqdm(total=total, desc=desc, disable=not enabled, leave=False, file=stream)
