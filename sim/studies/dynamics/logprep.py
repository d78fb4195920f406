"""What a user does by hand today to a controller log that the torque log reader refuses: the
benchmark's fallback, stated in its output (never applied silently).

:func:`prepare_by_hand` reads a CSV of :mod:`sim.studies.dynamics.reallog` (any of its
namings), maps the columns to the standard names, drops the rows that are exact copies of the
row before, and resamples the rest onto a constant step (the median step) by cubic
interpolation of positions and velocities and linear interpolation of the torques, across the
gaps too (the reader cannot be told where they are). RTDE-like currents are turned into
torques with the ``# torque_constant`` comment of the file (the controller's constants, part
of the log). It returns the standard :class:`~zrp.gap.dynamics.data.TorqueLog` and what was
done, in words.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog

__all__ = ["prepare_by_hand"]

#: The time column of each naming of :mod:`sim.studies.dynamics.reallog`.
_TIME = {"franka": "time", "rtde": "timestamp", "standard": "t [s]"}


def _naming(header: list[str]) -> str:
    for key, t in _TIME.items():
        if header[0] == t:
            return key
    raise InputError(f"header: unknown time column {header[0]!r}")


def _torque_constant(path: Path) -> np.ndarray | None:
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("# torque_constant"):
                return np.array([float(v) for v in line.split(":", 1)[1].split()])
    return None


def prepare_by_hand(path: str | os.PathLike[str]) -> tuple[TorqueLog, list[str]]:
    """The log of ``path`` as the standard reader wants it, and what was done (module
    docstring)."""
    path = Path(path)
    with open(path, encoding="utf-8") as fh:
        header = fh.readline().strip().split(",")
    naming = _naming(header)
    a = np.loadtxt(path, delimiter=",", skiprows=1, comments="#", ndmin=2)
    n = (a.shape[1] - 1) // 3
    done = [] if naming == "standard" else [f"columns renamed from the {naming} names"]
    keep = np.concatenate([[True], np.any(a[1:] != a[:-1], axis=1)])
    if not keep.all():
        done.append(f"{int((~keep).sum())} rows that repeat the row before dropped")
    a = a[keep]
    t, q, qd, eff = a[:, 0], a[:, 1:1 + n], a[:, 1 + n:1 + 2 * n], a[:, 1 + 2 * n:]
    if naming == "rtde":
        kt = _torque_constant(path)
        if kt is None or kt.shape != (n,):
            raise InputError(f"{path.name}: currents without a '# torque_constant' line")
        eff = eff * kt
        done.append("currents times the stated torque constants")
    dt = np.diff(t)
    step = float(np.median(dt))
    if np.any(np.abs(dt - step) > 0.05 * step):
        grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step)) + 1)
        q, qd = CubicSpline(t, q, axis=0)(grid), CubicSpline(t, qd, axis=0)(grid)
        eff = np.column_stack([np.interp(grid, t, eff[:, k]) for k in range(n)])
        done.append(f"resampled from {t.size} uneven time stamps (steps {dt.min() * 1e3:.2f} "
                    f"to {dt.max() * 1e3:.2f} ms) onto {grid.size} at {step * 1e3:.4g} ms")
        t = grid
    log = TorqueLog(t, q, qd, eff, None, None, np.arange(2, t.size + 2), path.name, "tau")
    return log, done
