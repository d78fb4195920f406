"""The paper's one-at-a-time perturbation study along a joint trajectory (Tables 2-3, Figs 2-7).

Each parameter (``LE{k}`` a link vector, ``JE{k}`` a joint axis, eqs 8-12) is perturbed alone
by each xi (percent) while the others stay at zero; the nominal inverse-kinematics joint values
are replayed on the perturbed arm and delta_p (eq 17), delta_R (eq 15) and the plain error
angle are recorded at every sample.

Joint trajectories (:class:`JointPath`) come from a nominal inverse-kinematics result
(:meth:`JointPath.from_ik`, e.g. of a circle: :func:`zrp.paper.scenario.circle_joint_path`) or
from a CSV file written by ``zrp ik`` (:func:`load_joint_csv`).
"""

from __future__ import annotations

import csv
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError, ZRPWarning
from zrp.escape import csv_text
from zrp.kinematics import _kernels as K
from zrp.kinematics._range_kernels import joint_limits
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.kinematics.ik import IKResult
from zrp.manufacturing.choices import PAPER_PARAMETERS, PAPER_XI
from zrp.manufacturing.perturb import (
    PAPER_SIGN_ZERO,
    Perturbation,
    check_xi_percent,
    parse_parameter,
)
from zrp.model.manipulator import Manipulator
from zrp.output import write_text
from zrp.rotations.rodrigues import er_angle, er_conjugate, er_multiply
from zrp.textio import iter_lines
from zrp.units import angle_bounds, joint_column_units, joint_values_to_rad, split_unit

__all__ = [
    "PAPER_PARAMETERS",
    "PAPER_XI",
    "JointPath",
    "Linearity",
    "StudyResult",
    "fit_linearity",
    "load_joint_csv",
    "one_at_a_time",
]




@dataclass(frozen=True, eq=False)
class JointPath:
    """A nominal joint trajectory.

    Attributes:
        t: times (s), shape (T,), non-decreasing.
        q: joint values, shape (T, n) (rad / length unit).
        label: description (trajectory, model, solver).
        ik_position_error: max |commanded - nominal FK| along the path (length unit), or None.
        ik_orientation_error_rad: the same for the orientation (rad), or None.
    """

    t: F64
    q: F64
    label: str = ""
    ik_position_error: float | None = None
    ik_orientation_error_rad: float | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        q = np.asarray(self.q, dtype=float)
        if q.ndim != 2 or q.shape[0] < 2:
            raise InputError(f"q: expected a joint trajectory of shape (T >= 2, n), got {q.shape}")
        if t.shape != (q.shape[0],):
            raise InputError(f"t: expected shape ({q.shape[0]},), got {t.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
            raise InputError("t, q: expected finite values")
        if np.any(np.diff(t) < 0):
            raise InputError("t: expected non-decreasing times")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)

    @classmethod
    def from_ik(cls, ik: IKResult, label: str = "") -> JointPath:
        """From a nominal inverse-kinematics result (keeps its tracking errors)."""
        return cls(ik.t, ik.q, label or ik.method, float(ik.position_error.max()),
                   float(ik.orientation_error.max()))


#: Most rows of a joint trajectory CSV (a path of 2 million steps is ~100 MB of numbers).
MAX_JOINT_ROWS = 2_000_000


def _read_rows(p: Path) -> list[list[str]]:
    """The CSV records, streamed (:func:`zrp.textio.iter_lines`: a regular file, lines
    bounded; at most :data:`MAX_JOINT_ROWS` rows)."""
    reader = csv.reader(iter_lines(p, label=str(p)))
    rows: list[list[str]] = []
    try:
        for row in reader:
            if len(rows) > MAX_JOINT_ROWS:
                raise InputError(f"{p}, line {reader.line_num}: more than {MAX_JOINT_ROWS:,} "
                                 "rows; thin the joint trajectory (every k-th step)")
            rows.append(row)
    except csv.Error as exc:
        raise InputError(f"{p}, line {reader.line_num}: not a CSV file ({exc})") from None
    return rows


def _time_and_joints(rows: list[list[str]], n: int, p: Path) -> F64:
    """t and q1..qn of each data row (after the header), finite numbers, shape (R, 1 + n)."""
    data = []
    for i, row in enumerate(rows[1:], start=2):
        if len(row) < n + 1:
            raise InputError(f"{p}, line {i}: expected at least {n + 1} columns (t, "
                             f"q1..q{n}), got {len(row)}")
        try:
            data.append([float(x) for x in row[:n + 1]])
        except ValueError as exc:
            raise InputError(f"{p}, line {i}: not a number: {exc}") from exc
        if not all(math.isfinite(v) for v in data[-1]):
            raise InputError(f"{p}, line {i}: expected finite numbers, got {row[:n + 1]}")
    return np.array(data)


def _joints_to_rad(q: F64, declared: list[str | None], model: Manipulator, deg: bool,
                   src: str) -> F64:
    """Joint columns by the unit rule of :mod:`zrp.units` (declared, or ``deg``), checked."""
    rev = ~np.asarray(model.prismatic)
    declared = declared + [None] * (model.n - len(declared))
    angle, scale = joint_column_units(declared, rev, deg, src=src, length_unit=model.length_unit)
    return joint_values_to_rad(q, rev, angle, src=src, lines=np.arange(2, len(q) + 2),
                               bounds=angle_bounds(model.lower, model.upper)) * scale


def load_joint_csv(path: str | Path, model: Manipulator, *, deg: bool = False) -> JointPath:
    """Read a joint trajectory CSV: a header row, time (s) in the first column and the n joint
    values in the next n columns (the layout ``zrp ik`` writes; rad / length unit, or degrees
    with ``deg``, or the unit a column declares, ``q1[deg]``: the rule and checks of
    :mod:`zrp.units`). The IK errors are taken from ``position_error`` /
    ``orientation_error_rad`` columns if present."""
    p = Path(path)
    rows = _read_rows(p)
    if len(rows) < 3:
        raise InputError(f"{p}: expected a header and at least 2 rows of t, q1..q{model.n}")
    arr = _time_and_joints(rows, model.n, p)
    parsed = [split_unit(h, f"{p}, line 1") for h in rows[0]]
    header = [h for h, _ in parsed]
    arr[:, 1:] = _joints_to_rad(arr[:, 1:], [u for _, u in parsed[1:model.n + 1]], model, deg,
                                str(p))
    errs: list[float | None] = []
    for col in ("position_error", "orientation_error_rad"):
        if col in header:  # written by `zrp ik` (IKResult.save_csv)
            j = header.index(col)
            try:
                errs.append(max(float(r[j]) for r in rows[1:]))
            except (ValueError, IndexError):
                errs.append(None)
        else:
            errs.append(None)
    return JointPath(arr[:, 0], arr[:, 1:], f"joint trajectory {p.name}", errs[0], errs[1])


@dataclass(frozen=True)
class Linearity:
    """Least-squares fit of max deviation = slope * |xi| + intercept over the study levels.

    Attributes:
        slope: per percent. intercept: at xi = 0. r2: coefficient of determination.
        slope_pos, slope_neg: slopes fitted separately on xi >= 0 and xi <= 0 (vs |xi|).
    """

    slope: float
    intercept: float
    r2: float
    slope_pos: float
    slope_neg: float


def _fit(x: F64, y: F64) -> tuple[float, float, float]:
    a = np.column_stack([x, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    ss_res = float(np.sum((y - a @ coef) ** 2))
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else (1.0 if ss_res == 0 else 0.0)
    return float(coef[0]), float(coef[1]), r2


def fit_linearity(xi: ArrayLike, y: ArrayLike) -> Linearity:
    """Fit y = slope |xi| + intercept (and per sign); xi in percent, shape (m,)."""
    xi = np.asarray(xi, dtype=float)
    y = np.asarray(y, dtype=float)
    if xi.shape != y.shape or np.unique(np.abs(xi)).size < 2:
        raise InputError(f"xi, y: expected equal shapes and at least two distinct |xi| levels, "
                         f"got xi {xi.tolist()}")
    slope, icpt, r2 = _fit(np.abs(xi), y)
    pos = xi >= 0
    neg = xi <= 0
    sp = _fit(np.abs(xi[pos]), y[pos])[0] if np.unique(xi[pos]).size >= 2 else float("nan")
    sn = _fit(np.abs(xi[neg]), y[neg])[0] if np.unique(xi[neg]).size >= 2 else float("nan")
    return Linearity(slope, icpt, r2, sp, sn)


@dataclass(frozen=True, eq=False)
class StudyResult:
    """Deviation histories of a one-at-a-time study.

    Attributes:
        parameters: names, P entries (``LE{k}`` / ``JE{k}``).
        xi_percent: levels, shape (m,), percent.
        t: times (s), shape (T,).
        delta_p: eq (17), shape (P, m, T), length unit.
        delta_r: eq (15) (paper's definition), shape (P, m, T), dimensionless.
        angle_rad: error angle theta_eps, shape (P, m, T), rad.
        sign_zero_links, sign_zero_axes: the sign(0) convention (eqs 10-11).
        unit: length unit.
        path: the joint trajectory used.
        model_name: the nominal model's name.
    """

    parameters: tuple[str, ...]
    xi_percent: F64
    t: F64
    delta_p: F64
    delta_r: F64
    angle_rad: F64
    sign_zero_links: int
    sign_zero_axes: int
    unit: str
    path: JointPath
    model_name: str = ""
    elapsed_s: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        shape = (len(self.parameters), np.size(self.xi_percent), np.size(self.t))
        for name in ("delta_p", "delta_r", "angle_rad"):
            if np.shape(getattr(self, name)) != shape:
                raise InputError(f"StudyResult.{name}: expected shape {shape}, got "
                                 f"{np.shape(getattr(self, name))}")

    @property
    def convention(self) -> str:
        return Perturbation({}, self.sign_zero_links, self.sign_zero_axes).convention

    @property
    def max_delta_p(self) -> F64:
        """max_t delta_p, shape (P, m)."""
        return self.delta_p.max(axis=-1)

    @property
    def max_delta_r(self) -> F64:
        """max_t delta_R (eq 15), shape (P, m)."""
        return self.delta_r.max(axis=-1)

    @property
    def max_angle_rad(self) -> F64:
        """max_t theta_eps, shape (P, m)."""
        return self.angle_rad.max(axis=-1)

    def index(self, parameter: str) -> int:
        try:
            return self.parameters.index(parameter.upper())
        except ValueError as exc:
            raise InputError(f"parameter {parameter!r}: not in this study "
                             f"({', '.join(self.parameters)})") from exc

    def linearity(self, quantity: str = "delta_p") -> dict[str, Linearity]:
        """Per parameter, the fit of max_t ``quantity`` against |xi| (empty when the study has
        fewer than two distinct |xi| levels)."""
        data = {"delta_p": self.max_delta_p, "delta_r": self.max_delta_r,
                "angle_rad": self.max_angle_rad}
        if quantity not in data:
            raise InputError(f"quantity: expected one of {sorted(data)}, got {quantity!r}")
        if np.unique(np.abs(self.xi_percent)).size < 2:
            return {}
        return {p: fit_linearity(self.xi_percent, data[quantity][i])
                for i, p in enumerate(self.parameters)}

    def table(self, quantity: str = "delta_p", parameters: Sequence[str] | None = None,
              xi_rows: Sequence[float] | None = None) -> tuple[list[str], list[list[float]]]:
        """Rows (xi, max per parameter) in the paper's layout: header and values."""
        data = {"delta_p": self.max_delta_p, "delta_r": self.max_delta_r,
                "angle_rad": self.max_angle_rad}[quantity]
        params = list(parameters or self.parameters)
        cols = [self.index(p) for p in params]
        rows = []
        for xi in (self.xi_percent if xi_rows is None else xi_rows):
            j = int(np.argmin(np.abs(self.xi_percent - xi)))
            if abs(self.xi_percent[j] - xi) > 1e-12:
                raise InputError(f"xi_rows: {xi} % is not a level of this study")
            rows.append([float(self.xi_percent[j]), *[float(data[c, j]) for c in cols]])
        return ["xi_percent", *params], rows

    def table_text(self, fmt: str = "csv", quantity: str = "delta_p",
                   parameters: Sequence[str] | None = None,
                   xi_rows: Sequence[float] | None = None, *, caption: str = "") -> str:
        """:meth:`table` as CSV (``fmt="csv"``) or Markdown (``fmt="md"``, with ``caption``)."""
        if fmt not in ("csv", "md"):
            raise InputError(f"fmt: expected 'csv' or 'md', got {fmt!r}")
        header, rows = self.table(quantity, parameters, xi_rows)
        if fmt == "csv":
            return csv_text(header, ([f"{r[0]:g}", *[f"{v:.6e}" for v in r[1:]]] for r in rows))
        lines = [caption, ""] if caption else []
        lines.append("| xi (%) | " + " | ".join(header[1:]) + " |")
        lines.append("|---:|" + "---:|" * (len(header) - 1))
        for r in rows:
            lines.append(f"| {r[0]:g} | " + " | ".join(f"{v:.2E}" for v in r[1:]) + " |")
        lines += ["", f"Sign convention: {self.convention}.", ""]
        return "\n".join(lines)

    def write_table(self, path: str | Path, quantity: str = "delta_p",
                    parameters: Sequence[str] | None = None,
                    xi_rows: Sequence[float] | None = None, *, overwrite: bool = False,
                    caption: str = "") -> Path:
        """Write :meth:`table` as CSV (``.csv``) or Markdown (any other suffix), atomically
        (:mod:`zrp.output`).

        Raises:
            OutputExistsError: ``path`` exists and ``overwrite`` is False.
        """
        fmt = "csv" if Path(path).suffix == ".csv" else "md"
        return write_text(path, self.table_text(fmt, quantity, parameters, xi_rows,
                                                caption=caption), overwrite=overwrite)

    def summary(self) -> dict[str, Any]:
        return {
            "model": self.model_name, "trajectory": self.path.label,
            "samples": int(self.t.size), "sign_convention": self.convention,
            "length_unit": self.unit, "xi_percent": self.xi_percent,
            "parameters": list(self.parameters),
            f"max_delta_p_{self.unit}": {p: self.max_delta_p[i]
                                         for i, p in enumerate(self.parameters)},
            "max_delta_R_eq15": {p: self.max_delta_r[i] for i, p in enumerate(self.parameters)},
            "max_angle_rad": {p: self.max_angle_rad[i] for i, p in enumerate(self.parameters)},
            "ik_max_position_error": self.path.ik_position_error,
            "ik_max_orientation_error_rad": self.path.ik_orientation_error_rad,
            "elapsed_s": self.elapsed_s,
        }


def one_at_a_time(model: Manipulator, path: JointPath,
                  parameters: Sequence[str] = PAPER_PARAMETERS,
                  xi_percent: Sequence[float] = PAPER_XI, *,
                  sign_zero_links: int = PAPER_SIGN_ZERO["links"],
                  sign_zero_axes: int = PAPER_SIGN_ZERO["axes"]) -> StudyResult:
    """Perturb each parameter alone by each xi and record the deviations along ``path``.

    Args:
        model: the nominal arm.
        path: nominal joint trajectory (:class:`JointPath`), q shape (T, n).
        parameters: names ``LE{k}`` (k = 1..n+1) / ``JE{k}`` (k = 1..n).
        xi_percent: levels in percent, each with -1 < xi < 1 (eq 8).
        sign_zero_links, sign_zero_axes: sign(0) in eqs (11) and (10).
    """
    import time

    if not isinstance(path, JointPath):
        raise InputError(f"path: expected a zrp.JointPath, got {type(path).__name__}")
    q = np.ascontiguousarray(check_q(model, path.q, "path.q"))
    if not parameters:
        raise InputError("parameters: expected at least one name such as LE2 or JE1")
    names = []
    for nm in parameters:
        kind, k = parse_parameter(nm, model)
        names.append(f"{kind}{k}")
    if len(set(names)) != len(names):
        raise InputError(f"parameters: duplicate names in {list(parameters)}")
    xis = np.array([check_xi_percent(x, f"xi {x!r}") for x in xi_percent], dtype=float)
    if xis.size == 0:
        raise InputError("xi_percent: expected at least one level")
    t0 = time.perf_counter()
    p_d, e_d = end_effector_pose(model, q)
    e_d_conj = er_conjugate(e_d)
    t_n = q.shape[0]
    shape = (len(names), xis.size, t_n)
    dp = np.empty(shape)
    ang = np.empty(shape)
    vec = np.empty(shape)
    out = np.empty((t_n, 7))
    prism = np.array(model.prismatic, dtype=np.bool_)
    lim = joint_limits(model)
    for i, nm in enumerate(names):
        for j, xi in enumerate(xis):
            pert = Perturbation({nm: xi}, sign_zero_links, sign_zero_axes)
            axes, bodies = pert.arrays(model)
            K.fk_pose_batch(q, np.ascontiguousarray(axes), np.ascontiguousarray(bodies), prism,
                            lim, out)  # q checked above
            dp[i, j] = np.linalg.norm(out[:, :3] - p_d, axis=-1)  # eq (17)
            e_err = er_multiply(out[:, 3:], e_d_conj)
            vec[i, j] = np.linalg.norm(e_err[:, 1:], axis=-1)
            ang[i, j] = er_angle(e_err)
    elapsed = time.perf_counter() - t0
    if sign_zero_axes == 0 and any(n.startswith("JE") for n in names):
        warnings.warn("sign_zero_axes = 0: a joint axis with a single nonzero component is "
                      "renormalised back to itself by eq (9), so its JE deviations vanish",
                      ZRPWarning, stacklevel=2)
    return StudyResult(tuple(names), xis, path.t, dp, np.sqrt(8.0) * vec, ang,
                       sign_zero_links, sign_zero_axes, model.length_unit, path, model.name,
                       elapsed)
