"""A torque channel frozen while its joint moves (issue 41 finding 6): a drive or a logger
that stops updating one joint's torque writes the last value again, row after row. Fitted as
data, half a log of one held value reads as a link tonnes heavier ("+136 kg").

A *frozen stretch* is a run of at least :data:`MIN_RUN` rows (and :data:`MIN_RUN_S` of time)
of exactly the same torque value while the joint's position moves (a real torque changes
when its joint moves: gravity, inertia, friction). A joint whose frozen stretches cover more
than :data:`SHARE` of the log is excluded from the fit, named with its stretches
(:attr:`~zrp.gap.dynamics.data.TorqueLog.unmeasured`); a shorter stretch is named in the
notes only. A joint at rest with a coarse sensor (identical values while it does not move)
is not frozen.
"""

from __future__ import annotations

import itertools

import numpy as np

from zrp.arrays import F64

__all__ = ["MIN_RUN", "MIN_RUN_S", "SHARE", "frozen_joints", "frozen_stretches"]

#: Fewest rows of one held torque value that can be a frozen stretch.
MIN_RUN = 50
#: Shortest frozen stretch, s.
MIN_RUN_S = 0.05
#: Share of the log in frozen stretches above which the joint's torque is not used.
SHARE = 0.2
_SHOWN = 3


def frozen_stretches(t: F64, q: F64, tau: F64) -> list[tuple[int, int]]:
    """The (start, stop) rows of each frozen stretch of one joint (module docstring)."""
    if tau.size < MIN_RUN:
        return []
    change = np.flatnonzero(np.diff(tau) != 0.0) + 1
    edges = np.concatenate([[0], change, [tau.size]])
    span = max(float(np.ptp(q)), 1e-12)
    out = []
    for a, b in itertools.pairwise(edges):
        if b - a < MIN_RUN or t[b - 1] - t[a] < MIN_RUN_S:
            continue
        if np.ptp(q[a:b]) > 0.01 * span:  # the joint moves while its torque is held
            out.append((int(a), int(b)))
    return out


def frozen_joints(t: F64, q: F64, tau: F64, lines: np.ndarray | None = None
                  ) -> tuple[dict[int, str], list[str]]:
    """Joints whose torque is frozen over more than :data:`SHARE` of the log, with why
    (for :attr:`TorqueLog.unmeasured`), and the notes on shorter frozen stretches."""
    out: dict[int, str] = {}
    notes: list[str] = []
    s = t.size
    for k in range(q.shape[1]):
        runs = frozen_stretches(t, q[:, k], tau[:, k])
        if not runs:
            continue
        rows = sum(b - a for a, b in runs)
        where = ", ".join(
            f"lines {lines[a]}-{lines[b - 1]}" if lines is not None else f"rows {a + 1}-{b}"
            for a, b in runs[:_SHOWN]) + (" ..." if len(runs) > _SHOWN else "")
        what = (f"torque frozen (one value held while the joint moves) over {rows} rows, "
                f"{rows / s:.0%} of the log ({where}): a stuck channel")
        if rows > SHARE * s:
            out[k] = what
        else:
            notes.append(f"joint {k + 1}: {what}; under {SHARE:.0%} of the log, kept")
    return out, notes
