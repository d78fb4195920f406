"""DH/MDH tables as data: export any model to a table (:func:`to_dh`), and read/write the
table as a TOML file (:func:`loads_dh`, :func:`dumps_dh`).

A DH table with a base and a tool transform can describe any chain of revolute and prismatic
joint axes (DH is complete for lines in space), so the export never fails for the joints; what
a table cannot hold is a base frame other than frame 0 or a tool other than frame n, which go
to ``base`` and ``tool``. The choices left free by the convention are fixed as follows
(canonical form): the x axes point along the common normal from one joint axis to the next
(a >= 0, alpha from the cross product when the axes intersect), d = 0 where consecutive axes
are parallel, and frame 0 has the world x axis projected onto it. A table in canonical form
(identity base and tool, which is how most tables are written) comes back identical; any
other comes back as an equivalent table with the same forward kinematics.

TOML layout (lengths in ``length_unit``, angles in rad)::

    convention = "standard"      # or "modified" (Craig)
    length_unit = "mm"
    base = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]   # optional
    tool = [[...]]                                                  # optional
    [[row]]
    a = 0.0
    alpha = -1.5707963267948966
    d = 0.0
    theta = 0.0        # constant part for a prismatic joint
    type = "revolute"
    offset = 0.0       # theta (or d) at q = 0
    flip = false       # optional
    limits = [-3.1, 3.1]   # optional
    name = "joint1"    # optional
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError, ModelFileError
from zrp.model.dh import DHRow, dh_forward, from_dh, from_mdh, mdh_forward
from zrp.model.manipulator import Manipulator

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["CONVENTIONS", "DHTable", "dumps_dh", "loads_dh", "to_dh"]

CONVENTIONS = ("standard", "modified")
_EPS = 1e-12


@dataclass(frozen=True, eq=False)
class DHTable:
    """Rows base to tip, ``base`` (world <- frame 0) and ``tool`` (frame n <- tool), shape
    (4, 4) each, in ``length_unit``."""

    rows: tuple[DHRow, ...]
    base: F64
    tool: F64
    convention: str = "standard"
    length_unit: str = "mm"
    name: str = "DH table"

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise InputError(f"convention: {self.convention!r} is unknown; expected one of "
                             f"{CONVENTIONS}")

    def model(self) -> Manipulator:
        """The ZRP model of the table."""
        make = from_dh if self.convention == "standard" else from_mdh
        return make(list(self.rows), base=self.base, tool=self.tool, name=self.name,
                    length_unit=self.length_unit)


def _unit(v: F64) -> F64:
    return v / np.linalg.norm(v)


def _angle(a: F64, b: F64, axis: F64) -> float:
    """Signed angle about ``axis`` taking ``a`` to ``b`` (both perpendicular to it)."""
    return float(np.arctan2(np.cross(a, b) @ axis, a @ b))


def _normal(o: F64, z: F64, p: F64, u: F64, x_prev: F64) -> tuple[float, F64, F64]:
    """Common normal from line (o, z) to line (p, u): (s along z from o, its foot on the
    second line, unit x along it). d = 0 (s = 0) when the lines are parallel."""
    c = np.cross(z, u)
    w = p - o
    if np.linalg.norm(c) > 1e-9:
        # closest points: o + s z and p + t u with (o + s z - p - t u) perpendicular to z, u
        b = z @ u
        s = float((w @ z - b * (w @ u)) / (1 - b * b))
        t = float((b * (w @ z) - w @ u) / (1 - b * b))
    else:
        s, t = 0.0, float(-(w @ u))
    foot = p + t * u
    r = foot - (o + s * z)
    if np.linalg.norm(r) > 1e-9 * max(1.0, float(np.linalg.norm(w))):
        return s, foot, _unit(r)
    if np.linalg.norm(c) > 1e-9:
        return s, foot, _unit(c)
    return s, foot, x_prev


def _frame(x: F64, z: F64, o: F64) -> F64:
    t = np.eye(4)
    t[:3, 0], t[:3, 1], t[:3, 2], t[:3, 3] = x, np.cross(z, x), z, o
    return t


def _row(model: Manipulator, k: int, a: float, alpha: float, d: float, theta: float) -> DHRow:
    j = model.joints[k]
    if j.is_prismatic:
        return DHRow(a=a, alpha=alpha, d=0.0, theta=theta, type="prismatic", offset=d,
                     limits=j.limits, name=j.name)
    return DHRow(a=a, alpha=alpha, d=d, theta=0.0, type="revolute", offset=theta,
                 limits=j.limits, name=j.name)


def _x_start(z: F64) -> F64:
    for cand in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        v = cand - (cand @ z) * z
        if np.linalg.norm(v) > 1e-6:
            return _unit(v)
    raise AssertionError("unreachable")  # pragma: no cover


def _last_x(z: F64, o: F64, pe: F64, xe: F64, x_prev: F64) -> tuple[float, F64, F64]:
    """Last frame: d along z to the tool point's foot, x toward the tool point (or the tool's
    x axis projected), as in the canonical rules."""
    d = float((pe - o) @ z)
    r = pe - o - d * z
    if np.linalg.norm(r) > 1e-9 * max(1.0, float(np.linalg.norm(pe - o))):
        return d, o + d * z, _unit(r)
    v = xe - (xe @ z) * z
    return d, o + d * z, (_unit(v) if np.linalg.norm(v) > 1e-6 else x_prev)


def to_dh(model: Manipulator, convention: str = "standard") -> DHTable:
    """The DH (``"standard"``) or modified-DH (``"modified"``, Craig) table of ``model`` in
    canonical form (module docstring), with the base and tool transforms it needs."""
    if convention not in CONVENTIONS:
        raise InputError(f"convention: {convention!r} is unknown; expected one of {CONVENTIONS}")
    n = model.n
    pts = np.cumsum(model.bodies, axis=0)  # point on joint k, then the tool point
    u = model.axes
    te = np.eye(4)
    te[:3, :3], te[:3, 3] = model.end_effector.frame, pts[n]
    rows: list[DHRow] = []
    if convention == "standard":
        z, o = u[0], pts[0] - (pts[0] @ u[0]) * u[0]   # frame 0 on joint 1's axis
        x = _x_start(z)
        base = _frame(x, z, o)
        for k in range(n):
            if k < n - 1:
                s, o_new, x_new = _normal(o, z, pts[k + 1], u[k + 1], x)
                z_new = u[k + 1]
            else:
                s, foot, x_new = _last_x(z, o, pts[n], te[:3, 0], x)
                o_new = foot + ((pts[n] - foot) @ x_new) * x_new  # a along x_n to the tool
                ze = te[:3, 2]
                z_new = _unit(ze - (ze @ x_new) * x_new) if abs(ze @ x_new) < 1 - 1e-12 else z
            a = float((o_new - (o + s * z)) @ x_new)
            rows.append(_row(model, k, a, _angle(z, z_new, x_new), s, _angle(x, x_new, z)))
            x, z, o = x_new, z_new, o_new
    else:
        z = np.array([0, 0, 1.0])  # frame 0 along the world z axis
        s, _, x = _normal(np.zeros(3), z, pts[0], u[0], np.array([1.0, 0, 0]))
        o = s * z
        base = _frame(x, z, o)
        for k in range(n):
            _, foot, _ = _normal(o, z, pts[k], u[k], x)
            a = float((foot - o) @ x)
            alpha = _angle(z, u[k], x)
            if k < n - 1:
                s, o_new, x_new = _normal(foot, u[k], pts[k + 1], u[k + 1], x)
                o_new = foot + s * u[k]
            else:
                s, o_new, x_new = _last_x(u[k], foot, pts[n], te[:3, 0], x)
            rows.append(_row(model, k, a, alpha, s, _angle(x, x_new, u[k])))
            x, z, o = x_new, u[k], o_new
    table = DHTable(tuple(rows), base, np.eye(4), convention, model.length_unit, model.name)
    frame_n = _chain(table)
    tool = np.linalg.solve(frame_n, te)
    tool[np.abs(tool) < _EPS] = 0.0
    tool[3] = [0, 0, 0, 1]
    return DHTable(tuple(rows), _clean(base), tool, convention, model.length_unit, model.name)


def _clean(t: F64) -> F64:
    t = t.copy()
    t[np.abs(t) < _EPS] = 0.0
    return t


def _chain(table: DHTable) -> F64:
    """Frame n at q = 0 (base included, tool excluded)."""
    fwd = dh_forward if table.convention == "standard" else mdh_forward
    return fwd(list(table.rows), np.zeros(len(table.rows)), base=table.base)


def _fmt(x: float) -> str:
    return repr(float(x))


def dumps_dh(table: DHTable) -> str:
    """The table as TOML text (layout in the module docstring)."""
    def mat(m: F64) -> str:
        return "[" + ", ".join("[" + ", ".join(_fmt(v) for v in r) + "]" for r in m) + "]"
    name = table.name.replace("\\", "\\\\").replace('"', '\\"')
    out = [f'name = "{name}"', f'convention = "{table.convention}"',
           f'length_unit = "{table.length_unit}"', f"base = {mat(table.base)}",
           f"tool = {mat(table.tool)}", ""]
    for r in table.rows:
        out.append("[[row]]")
        if r.name:
            out.append('name = "' + r.name.replace("\\", "\\\\").replace('"', '\\"') + '"')
        out += [f"a = {_fmt(r.a)}", f"alpha = {_fmt(r.alpha)}", f"d = {_fmt(r.d)}",
                f"theta = {_fmt(r.theta)}", f'type = "{r.type}"', f"offset = {_fmt(r.offset)}"]
        if r.flip:
            out.append("flip = true")
        if r.limits is not None:
            out.append(f"limits = [{_fmt(r.limits[0])}, {_fmt(r.limits[1])}]")
        out.append("")
    return "\n".join(out)


def loads_dh(text: str, source: str = "<string>") -> DHTable:
    """Parse a DH table TOML text. Errors name ``source`` and the row or key."""
    try:
        data: dict[str, Any] = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{source}: not valid TOML: {exc}") from exc
    allowed = {"name", "convention", "length_unit", "base", "tool", "row"}
    bad = sorted(set(data) - allowed)
    if bad:
        raise ModelFileError(f"{source}: unknown key {bad[0]!r}; expected one of "
                             f"{sorted(allowed)}")
    rows_raw = data.get("row")
    if not isinstance(rows_raw, list) or not rows_raw:
        raise ModelFileError(f"{source}: no [[row]] tables; a DH table needs at least one row")
    try:
        rows = tuple(DHRow(**{k: (tuple(v) if k == "limits" else v) for k, v in r.items()})
                     for r in rows_raw)
        base = np.array(data.get("base", np.eye(4)), dtype=float)
        tool = np.array(data.get("tool", np.eye(4)), dtype=float)
        table = DHTable(rows, base, tool, str(data.get("convention", "standard")),
                        str(data.get("length_unit", "mm")), str(data.get("name", source)))
        table.model()  # validates the transforms and rows
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{source}: {exc}") from exc
    return table
