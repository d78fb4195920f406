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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator, check_limits

__all__ = ["DHRow", "dh_forward", "from_dh", "from_mdh", "mdh_forward"]



@dataclass(frozen=True)
class DHRow:
    """One row of a DH table. Lengths in the model's unit, angles in rad.

    ``offset`` is theta's value at the zero reference for a revolute joint, d's for a
    prismatic one; the other of (theta, d) is the constant ``theta``/``d`` field. ``flip``
    reverses the joint (Robotics Toolbox's ``flip``): theta = offset - q (or d = offset - q),
    so the ZRP axis is -z. ``limits`` (Robotics Toolbox's ``qlim``) bounds q, rad or length
    unit. Rows are best given by name (``DHRow(a=..., alpha=..., d=...)`` or a dict with those
    keys); a plain sequence is read in the order (a, alpha, d, theta, type, offset).
    """

    a: float
    alpha: float
    d: float = 0.0
    theta: float = 0.0
    type: str = "revolute"
    offset: float = 0.0
    flip: bool = False
    limits: tuple[float, float] | None = None
    name: str = ""

    def __post_init__(self) -> None:
        if self.type not in ("revolute", "prismatic"):
            raise InputError(f"DH row type: {self.type!r}; expected 'revolute' or 'prismatic'")
        for name in ("a", "alpha", "d", "theta", "offset"):
            v = getattr(self, name)
            if not isinstance(v, (int, float, np.integer, np.floating)) or isinstance(v, bool) \
                    or not np.isfinite(float(v)):
                raise InputError(f"DH row {name}: expected a finite number, got {v!r}")
        if self.limits is not None:
            object.__setattr__(self, "limits", check_limits(self.limits, "DH row limits"))


def _rows(rows: Sequence[DHRow | Sequence[float]]) -> list[DHRow]:
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise InputError(f"rows: expected a sequence of DH rows (a, alpha, d, theta), got "
                         f"{type(rows).__name__}")
    out = []
    known = [f.name for f in fields(DHRow)]
    for i, r in enumerate(rows, start=1):
        if isinstance(r, DHRow):
            out.append(r)
        elif isinstance(r, Mapping):
            bad = sorted(set(r) - set(known))
            if bad:
                raise InputError(f"DH row {i}: unknown field {bad[0]!r}; expected {known}")
            try:
                out.append(DHRow(**r))
            except TypeError as exc:
                raise InputError(f"DH row {i}: {exc}; expected fields {known}") from exc
        else:
            try:
                if len(r) > 6:  # flip, limits, name: by name only
                    raise TypeError("too many positional fields")
                out.append(DHRow(*r))  # type: ignore[arg-type]
            except (TypeError, ValueError) as exc:
                if isinstance(exc, InputError):
                    raise InputError(f"DH row {i}: {exc}") from exc
                raise InputError(f"DH row {i}: expected (a, alpha, d, theta[, type, offset]) "
                                 f"(other fields by name), got {r!r}") from exc
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
    if row.flip:
        qk = -qk
    if row.type == "revolute":
        return row.offset + qk, row.d
    return row.theta, row.offset + qk


def _mat(t: ArrayLike | None, name: str) -> F64:
    """A 4x4 homogeneous transform (identity for None)."""
    if t is None:
        return np.eye(4)
    m = np.array(t, dtype=float)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)) or not np.allclose(m[3], [0, 0, 0, 1]):
        raise InputError(f"{name}: expected a 4x4 homogeneous transform, got shape {m.shape}")
    if not np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9):
        raise InputError(f"{name}: the rotation block is not orthonormal")
    return m


def dh_forward(rows: Sequence[DHRow | Sequence[float]], q: ArrayLike,
               tool: ArrayLike | None = None, base: ArrayLike | None = None) -> F64:
    """Direct standard-DH chain base @ A_1 ... A_n @ tool: the tool's transform, (4, 4)."""
    rs = _rows(rows)
    q = np.asarray(q, dtype=float)
    t = _mat(base, "base")
    for row, qk in zip(rs, q, strict=True):
        th, d = _joint_values(row, float(qk))
        t = t @ _rz(th) @ _tz(d) @ _tx(row.a) @ _rx(row.alpha)
    return t @ _mat(tool, "tool")


def mdh_forward(rows: Sequence[DHRow | Sequence[float]], q: ArrayLike,
                tool: ArrayLike | None = None, base: ArrayLike | None = None) -> F64:
    """Direct modified-DH (Craig) chain: the tool's homogeneous transform, shape (4, 4).

    Row k holds (a_{k-1}, alpha_{k-1}, d_k, theta_k)."""
    rs = _rows(rows)
    q = np.asarray(q, dtype=float)
    t = _mat(base, "base")
    for row, qk in zip(rs, q, strict=True):
        th, d = _joint_values(row, float(qk))
        t = t @ _rx(row.alpha) @ _tx(row.a) @ _rz(th) @ _tz(d)
    return t @ _mat(tool, "tool")


def _to_model(frames_joint: list[F64], tool_t: F64, rs: list[DHRow], name: str,
              length_unit: str) -> Manipulator:
    n = len(rs)
    types = [r.type for r in rs]
    pts = [f[:3, 3] for f in frames_joint]
    axes = np.array([f[:3, 2] * (-1.0 if r.flip else 1.0) for f, r in zip(frames_joint, rs,
                                                                         strict=True)])
    bodies = np.zeros((n + 1, 3))
    prev = np.zeros(3)
    for k in range(n):
        bodies[k] = pts[k] - prev
        prev = pts[k]
    bodies[n] = tool_t[:3, 3] - prev
    return Manipulator.from_arrays(axes, bodies, axial=tool_t[:3, 2], transverse=tool_t[:3, 1],
                                   types=types, name=name, length_unit=length_unit,
                                   limits=[r.limits for r in rs],
                                   joint_names=[r.name for r in rs])


def from_dh(rows: Sequence[DHRow | Sequence[float]], *, tool: ArrayLike | None = None,
            base: ArrayLike | None = None, name: str = "from DH",
            length_unit: str = "mm") -> Manipulator:
    """Standard DH table (rows base to tip) -> :class:`Manipulator`.

    Joint k's axis is z_{k-1} (negated for a flipped joint) through the origin of frame k-1,
    evaluated at the zero reference. ``base`` (world <- frame 0) and ``tool`` (frame n <- tool)
    are 4x4 transforms (lengths in ``length_unit``); the model is expressed in the world frame.
    """
    rs = _rows(rows)
    t = _mat(base, "base")
    frames = []
    for row in rs:
        frames.append(t.copy())
        th, d = _joint_values(row, 0.0)
        t = t @ _rz(th) @ _tz(d) @ _tx(row.a) @ _rx(row.alpha)
    tool_t = t @ _mat(tool, "tool")
    return _to_model(frames, tool_t, rs, name, length_unit)


def from_mdh(rows: Sequence[DHRow | Sequence[float]], *, tool: ArrayLike | None = None,
             base: ArrayLike | None = None, name: str = "from modified DH",
             length_unit: str = "mm") -> Manipulator:
    """Modified (Craig) DH table -> :class:`Manipulator`. Joint k's axis is z_k (negated for a
    flipped joint); ``base`` and ``tool`` as in :func:`from_dh`."""
    rs = _rows(rows)
    t = _mat(base, "base")
    frames = []
    for row in rs:
        t = t @ _rx(row.alpha) @ _tx(row.a)
        frames.append(t.copy())
        th, d = _joint_values(row, 0.0)
        t = t @ _rz(th) @ _tz(d)
    tool_t = t @ _mat(tool, "tool")
    return _to_model(frames, tool_t, rs, name, length_unit)
