"""Timings that hold under load: CPU time beside wall time, A/B rounds interleaved, the load
average recorded (issue 34).

On a shared machine the wall-clock time of a call grows with the other processes' load (at a
load of 12 on 2 cores a wall-clock benchmark reported its kernel 3x slower and its ratio to
MuJoCo 6x off). The CPU time this process spends (``time.process_time``: all its threads) is
what the code costs; it is what the tables rank by, with the wall time beside it. The calls
compared are timed in turn within each round (A B C, A B C, ...), so that a change of load
during the run slows them alike, and the best of the rounds is kept. The 1-minute load
average before and after the rounds goes with the numbers (the report's header has the run's).

Typical use::

    a, b = interleaved(lambda: f(x), lambda: g(x), repeat=9)
    print(a.cpu / b.cpu, a.wall, a.load)
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["Timing", "interleaved", "load_average"]


def load_average() -> float:
    """The 1-minute load average (nan where the system has none)."""
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


@dataclass(frozen=True)
class Timing:
    """One call's best time over the rounds.

    Attributes:
        cpu: best CPU time of this process (all threads), s.
        wall: best wall-clock time, s.
        load: the 1-minute load average at the start and at the end of the rounds.
    """

    cpu: float
    wall: float
    load: tuple[float, float]

    def text(self, per: float = 1.0) -> str:
        """``cpu`` and ``wall`` divided by ``per`` (e.g. a per-item time), in words."""
        return (f"CPU {self.cpu / per:.4g} s, wall {self.wall / per:.4g} s "
                f"(load {self.load[0]:.1f}-{self.load[1]:.1f})")


def interleaved(*fns: Callable[[], object], repeat: int = 9,
                warmup: bool = True) -> list[Timing]:
    """Best CPU and wall time of each of ``fns``, timed in turn within each of ``repeat``
    rounds (after one untimed call of each when ``warmup``: compilation, caches)."""
    if warmup:
        for fn in fns:
            fn()
    start = load_average()
    cpu: list[list[float]] = [[] for _ in fns]
    wall: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            cpu[i].append(time.process_time() - c0)
            wall[i].append(time.perf_counter() - w0)
    end = load_average()
    return [Timing(min(c), min(w), (start, end)) for c, w in zip(cpu, wall, strict=True)]
