"""The physical domain of a torque log, checked wherever one is built (the reader, or
:class:`zrp.gap.dynamics.data.TorqueLog` through the Python API): array types and shapes
consistent, every value finite and within a physical bound, time strictly increasing,
segments that tile the samples. A value outside is an :class:`~zrp.errors.InputError`
naming the field, the joint and the file line (or row), never a clamp.

Bounds (generous: they catch units and corruption, not unusual arms): joint positions within
+-:data:`Q_MAX` (two turns; beyond it in a column read as radians the values look like
degrees), velocities within +-:data:`QD_MAX` rad/s, torques within +-:data:`TAU_MAX` N m,
a payload within 0..:data:`PAYLOAD_MAX` kg (the largest industrial arms carry 2.3 t).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from zrp.errors import InputError

__all__ = ["PAYLOAD_MAX", "QD_MAX", "Q_MAX", "TAU_MAX", "check_log", "unmeasured_joints"]

Q_MAX = 4.0 * math.pi
QD_MAX = 1e3
TAU_MAX = 1e6
PAYLOAD_MAX = 1e4

_BOUNDS = {"q": (-Q_MAX, Q_MAX, "rad (m for slides)"), "qd": (-QD_MAX, QD_MAX, "rad/s"),
           "tau": (-TAU_MAX, TAU_MAX, "N m"), "qc": (-Q_MAX, Q_MAX, "rad (m for slides)"),
           "payload": (0.0, PAYLOAD_MAX, "kg")}


def _array(log: Any, name: str, ndim: int) -> np.ndarray | None:
    x = getattr(log, name)
    if x is None:
        return None
    try:
        a = np.array(x, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"TorqueLog.{name}: not an array of numbers ({exc})") from None
    if a.ndim != ndim:
        raise InputError(f"TorqueLog.{name}: {a.ndim}-dimensional (shape {a.shape}); expected "
                         f"{ndim} dimension(s)")
    object.__setattr__(log, name, a)
    return a


def _where(log: Any, row: int) -> str:
    lines = log.lines
    return (f"{log.source} line {int(lines[row])}" if lines.size == log.t.size
            else f"{log.source} row {row}")


def _bounded(log: Any, name: str, a: np.ndarray) -> None:
    lo, hi, unit = _BOUNDS[name]
    bad = ~np.isfinite(a) | (a < lo) | (a > hi)
    if not bad.any():
        return
    idx = np.argwhere(bad)[0]
    row = int(idx[0])
    col = f"{name}{int(idx[1]) + 1}" if a.ndim == 2 else name
    v = float(a[tuple(idx)])
    hint = ""
    if name in ("q", "qc") and math.isfinite(v) and abs(v) <= 360.0 * 4:
        hint = "; the values look like degrees: declare the unit, e.g. q1 [deg]"
    raise InputError(f"{_where(log, row)}: column {col} is {v:.6g} {unit.split(' ')[0]}, outside "
                     f"the physical domain [{lo:g}, {hi:g}] {unit}{hint}")


def _shapes(log: Any) -> tuple[np.ndarray, np.ndarray]:
    t = _array(log, "t", 1)
    q = _array(log, "q", 2)
    if t is None or q is None:
        raise InputError("TorqueLog.t and TorqueLog.q: required")
    s = t.size
    if s < 2:
        raise InputError(f"TorqueLog.t: {s} sample(s); a torque log needs a time series")
    if q.shape[0] != s or q.shape[1] < 1:
        raise InputError(f"TorqueLog.q: shape {q.shape}; expected ({s}, n >= 1) for the {s} "
                         "samples of t")
    for name in ("qd", "tau", "qc"):
        a = _array(log, name, 2)
        if a is None and name == "tau":
            raise InputError("TorqueLog.tau: required (the measured joint torques)")
        if a is not None and a.shape != q.shape:
            raise InputError(f"TorqueLog.{name}: shape {a.shape}, but q is {q.shape}")
    p = _array(log, "payload", 1)
    if p is not None and p.size != s:
        raise InputError(f"TorqueLog.payload: {p.size} values for {s} samples")
    lines = np.asarray(log.lines)
    if lines.size not in (0, s) or lines.ndim != 1:
        raise InputError(f"TorqueLog.lines: shape {lines.shape}; expected ({s},) or empty")
    return t, q


def _segments(log: Any, s: int) -> None:
    segs = log.segments
    try:
        flat = [(int(a), int(b)) for a, b in segs]
    except (TypeError, ValueError) as exc:
        raise InputError(f"TorqueLog.segments: not (start, stop) pairs ({exc})") from None
    if not flat:
        return
    ends = [0] + [b for _, b in flat]
    if any(a != e or b <= a for (a, b), e in zip(flat, ends, strict=False)) or ends[-1] != s:
        raise InputError(f"TorqueLog.segments: {flat[:4]}... must tile the {s} samples "
                         "(start 0, each starting where the previous stops, the last at "
                         f"{s})")
    object.__setattr__(log, "segments", tuple(flat))


def check_log(log: Any) -> None:
    """Check (and coerce to float arrays) the fields of ``log`` (module docstring)."""
    t, q = _shapes(log)
    if not np.all(np.isfinite(t)):
        raise InputError(f"{_where(log, int(np.argmin(np.isfinite(t))))}: t is not finite")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        raise InputError(f"{_where(log, int(bad[0]) + 1)}: t does not increase; samples must "
                         "be in time order, one per time stamp")
    for name in ("q", "qd", "tau", "qc", "payload"):
        a = getattr(log, name)
        if a is not None:
            _bounded(log, name, a)
    _segments(log, t.size)
    n = q.shape[1]
    if any(not isinstance(k, int | np.integer) or not 0 <= k < n for k in log.unmeasured):
        raise InputError(f"TorqueLog.unmeasured: joint indices must be 0..{n - 1}, got "
                         f"{sorted(log.unmeasured)}")


def unmeasured_joints(q: np.ndarray, tau: np.ndarray) -> dict[int, str]:
    """Joints whose torque never changes or whose position never moves, with the reason."""
    out: dict[int, str] = {}
    for k in range(q.shape[1]):
        if np.ptp(tau[:, k]) == 0.0:
            v = float(tau[0, k])
            out[k] = ("torque exactly zero over the whole log (not logged)" if v == 0.0 else
                      f"torque constant at {v:.6g} N m over the whole log (not measured)")
        elif np.ptp(q[:, k]) == 0.0:
            out[k] = f"position never moves (constant {float(q[0, k]):.6g})"
    return out
