"""Conversions from Denavit-Hartenberg tables to the zero-reference-position model.

Two conventions are supported:

* standard DH (``from_dh``): A_k = Rz(theta_k) Tz(d_k) Tx(a_k) Rx(alpha_k); joint k moves about
  (or along) z_{k-1}.
* modified DH, Craig's (``from_mdh``): A_k = Rx(alpha_{k-1}) Tx(a_{k-1}) Rz(theta_k) Tz(d_k);
  joint k moves about (or along) z_k.

The zero reference position is the configuration where every joint variable is at its offset
(theta_k = offset_k for revolute, d_k = offset_k for prismatic joints), so ZRP joint values are
q_k = theta_k - offset_k (or d_k - offset_k). The end effector is the origin of the last frame
(times an optional tool transform); its axial vector is the tool z axis and its transverse
vector the tool y axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.errors import InputError
from zrp.model.manipulator import Manipulator

__all__ = ["DHRow", "dh_forward", "from_dh", "from_mdh", "mdh_forward"]

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class DHRow:
    """One row of a DH table. Lengths in the model's unit, angles in rad.

    ``offset`` is theta's value at the zero reference for a revolute joint, d's for a
    prismatic one; the other of (theta, d) is the constant ``theta``/``d`` field.
    """

    a: float
    alpha: float
    d: float = 0.0
    theta: float = 0.0
    type: str = "revolute"
    offset: float = 0.0

    def __post_init__(self) -> None:
        if self.type not in ("revolute", "prismatic"):
            raise InputError(f"DH row type: {self.type!r}; expected 'revolute' or 'prismatic'")
        for name in ("a", "alpha", "d", "theta", "offset"):
            v = getattr(self, name)
            if not isinstance(v, (int, float, np.integer, np.floating)) or isinstance(v, bool) \
                    or not np.isfinite(float(v)):
                raise InputError(f"DH row {name}: expected a finite number, got {v!r}")


def _rows(rows: Sequence[DHRow | Sequence[float]]) -> list[DHRow]:
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise InputError(f"rows: expected a sequence of DH rows (a, alpha, d, theta), got "
                         f"{type(rows).__name__}")
    out = []
    for i, r in enumerate(rows, start=1):
        if isinstance(r, DHRow):
            out.append(r)
        else:
            try:
                out.append(DHRow(*r))  # type: ignore[arg-type]
            except (TypeError, ValueError) as exc:
                if isinstance(exc, InputError):
                    raise InputError(f"DH row {i}: {exc}") from exc
                raise InputError(f"DH row {i}: expected (a, alpha, d, theta[, type, offset]), "
                                 f"got {r!r}") from exc
    if not out:
        raise InputError("DH table: expected at least one row")
    return out


def _rz(t: float) -> F64:
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _rx(t: float) -> F64:
    c, s = np.cos(t), np.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _tz(d: float) -> F64:
    m = np.eye(4)
    m[2, 3] = d
    return m


def _tx(a: float) -> F64:
    m = np.eye(4)
    m[0, 3] = a
    return m


def _joint_values(row: DHRow, qk: float) -> tuple[float, float]:
    if row.type == "revolute":
        return row.offset + qk, row.d
    return row.theta, row.offset + qk


def dh_forward(rows: Sequence[DHRow | Sequence[float]], q: ArrayLike,
               tool: ArrayLike | None = None) -> F64:
    """Direct standard-DH chain: the tool's homogeneous transform, shape (4, 4)."""
    rs = _rows(rows)
    q = np.asarray(q, dtype=float)
    t = np.eye(4)
    for row, qk in zip(rs, q, strict=True):
        th, d = _joint_values(row, float(qk))
        t = t @ _rz(th) @ _tz(d) @ _tx(row.a) @ _rx(row.alpha)
    return t @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float))


def mdh_forward(rows: Sequence[DHRow | Sequence[float]], q: ArrayLike,
                tool: ArrayLike | None = None) -> F64:
    """Direct modified-DH (Craig) chain: the tool's homogeneous transform, shape (4, 4).

    Row k holds (a_{k-1}, alpha_{k-1}, d_k, theta_k)."""
    rs = _rows(rows)
    q = np.asarray(q, dtype=float)
    t = np.eye(4)
    for row, qk in zip(rs, q, strict=True):
        th, d = _joint_values(row, float(qk))
        t = t @ _rx(row.alpha) @ _tx(row.a) @ _rz(th) @ _tz(d)
    return t @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float))


def _to_model(frames_joint: list[F64], tool_t: F64, types: list[str], name: str,
              length_unit: str) -> Manipulator:
    n = len(types)
    pts = [f[:3, 3] for f in frames_joint]
    axes = np.array([f[:3, 2] for f in frames_joint])
    bodies = np.zeros((n + 1, 3))
    prev = np.zeros(3)
    for k in range(n):
        bodies[k] = pts[k] - prev
        prev = pts[k]
    bodies[n] = tool_t[:3, 3] - prev
    return Manipulator.from_arrays(axes, bodies, axial=tool_t[:3, 2], transverse=tool_t[:3, 1],
                                   types=types, name=name, length_unit=length_unit)


def from_dh(rows: Sequence[DHRow | Sequence[float]], *, tool: ArrayLike | None = None,
            name: str = "from DH", length_unit: str = "mm") -> Manipulator:
    """Standard DH table (rows base to tip) -> :class:`Manipulator`.

    Joint k's axis is z_{k-1} through the origin of frame k-1, evaluated at the zero reference.
    """
    rs = _rows(rows)
    t = np.eye(4)
    frames = []
    for row in rs:
        frames.append(t.copy())
        th, d = _joint_values(row, 0.0)
        t = t @ _rz(th) @ _tz(d) @ _tx(row.a) @ _rx(row.alpha)
    tool_t = t @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float))
    return _to_model(frames, tool_t, [r.type for r in rs], name, length_unit)


def from_mdh(rows: Sequence[DHRow | Sequence[float]], *, tool: ArrayLike | None = None,
             name: str = "from modified DH", length_unit: str = "mm") -> Manipulator:
    """Modified (Craig) DH table -> :class:`Manipulator`. Joint k's axis is z_k."""
    rs = _rows(rows)
    t = np.eye(4)
    frames = []
    for row in rs:
        t = t @ _rx(row.alpha) @ _tx(row.a)
        frames.append(t.copy())
        th, d = _joint_values(row, 0.0)
        t = t @ _rz(th) @ _tz(d)
    tool_t = t @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float))
    return _to_model(frames, tool_t, [r.type for r in rs], name, length_unit)
