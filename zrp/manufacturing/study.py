"""The paper's one-at-a-time perturbation study along a joint trajectory (Tables 2-3, Figs 2-7).

Each parameter (``LE{k}`` a link vector, ``JE{k}`` a joint axis, eqs 8-12) is perturbed alone
by each xi (percent) while the others stay at zero; the nominal inverse-kinematics joint values
are replayed on the perturbed arm and delta_p (eq 17), delta_R (eq 15) and the plain error
angle are recorded at every sample.

Joint trajectories (:class:`JointPath`) come from the nominal inverse kinematics of a circle
(:func:`circle_joint_path`, the paper's 125 mm circle by default), from an
:class:`~zrp.kinematics.ik.IKResult`, or from a CSV file written by ``zrp ik``.
"""

from __future__ import annotations

import csv
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.errors import InputError, ModelFileError, OutputExistsError, ZRPWarning
from zrp.kinematics import _kernels as K
from zrp.kinematics.forward import check_q, end_effector_pose, forward_kinematics
from zrp.kinematics.ik import IKResult, track_trajectory
from zrp.manufacturing.perturb import (
    PAPER_SIGN_ZERO,
    Perturbation,
    check_xi_percent,
    parse_parameter,
)
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import er_angle, er_conjugate, er_multiply

__all__ = [
    "PAPER_PARAMETERS",
    "PAPER_XI",
    "JointPath",
    "Linearity",
    "StudyResult",
    "circle_joint_path",
    "fit_linearity",
    "load_joint_csv",
    "one_at_a_time",
]

F64 = NDArray[np.float64]

#: The perturbation levels of the paper's study, in percent.
PAPER_XI: tuple[float, ...] = (-0.1, -0.07, -0.05, -0.02, 0.0, 0.02, 0.05, 0.07, 0.1)
#: The perturbed parameters of the paper's study (links 5 and 6 have zero length).
PAPER_PARAMETERS: tuple[str, ...] = ("LE2", "LE3", "LE4", "LE7", "JE1", "JE2", "JE3", "JE4",
                                     "JE5", "JE6")


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


def circle_joint_path(model: Manipulator, *, q0: ArrayLike | None = None,
                      radius: float = 125.0, duration: float = 4.0, steps: int = 360,
                      normal: ArrayLike | None = None, toward: ArrayLike | None = None,
                      time_law: str = "quintic") -> JointPath:
    """Nominal inverse kinematics of a circle through the end-effector point at ``q0``.

    Defaults reproduce :func:`zrp.paper.scenario.puma_circle` for the PUMA: q0 = (0, 0, 0, 0, 90, 0)
    deg, the circle's plane normal is the tool's axial direction u_a at q0, the centre lies
    ``radius`` above the start (base +z projected into the plane; base +x if z is normal to it).

    Args:
        q0: start configuration, shape (n,) (rad / length unit); default the PUMA's for 6-joint
            arms, required otherwise.
        radius: length unit. duration: s. steps: integration steps (T = steps + 1 samples).
    """
    from zrp.kinematics.trajectory import Circle
    from zrp.paper.scenario import PUMA_Q0_DEG

    if q0 is None:
        if model.n != 6:
            raise InputError(f"q0: required for {model.name!r} ({model.n} joints); the default "
                             f"start configuration is the 6-joint PUMA's")
        q0 = np.radians(PUMA_Q0_DEG)
    q0 = np.asarray(check_q(model, q0, "q0"), dtype=float)
    if q0.shape != (model.n,):
        raise InputError(f"q0: expected shape ({model.n},), got {q0.shape}")
    fk = forward_kinematics(model, q0)
    nrm = fk.axial if normal is None else np.asarray(normal, dtype=float)
    if toward is None:
        nn = nrm / max(float(np.linalg.norm(nrm)), 1e-300)
        z = np.array([0.0, 0.0, 1.0])
        toward = z if np.linalg.norm(z - (z @ nn) * nn) > 1e-6 else np.array([1.0, 0.0, 0.0])
    circle = Circle.from_start(fk.position, radius, nrm, toward, duration=duration,
                               time_law=time_law)
    ik = track_trajectory(model, circle, q0, steps)
    return JointPath.from_ik(ik, f"{radius:g} {model.length_unit} circle, {steps} steps, "
                                 f"{duration:g} s, {ik.method}")


def load_joint_csv(path: str | Path, model: Manipulator) -> JointPath:
    """Read a joint trajectory CSV: a header row, time (s) in the first column and the n joint
    values in the next n columns (the layout ``zrp ik`` writes; rad / length unit). The IK
    errors are taken from ``position_error`` / ``orientation_error_rad`` columns if present."""
    p = Path(path)
    try:
        with p.open(newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise ModelFileError(f"{p}: cannot read joint trajectory: {exc}") from exc
    if len(rows) < 3:
        raise InputError(f"{p}: expected a header and at least 2 rows of t, q1..q{model.n}")
    data = []
    for i, row in enumerate(rows[1:], start=2):
        if len(row) < model.n + 1:
            raise InputError(f"{p}, line {i}: expected at least {model.n + 1} columns (t, "
                             f"q1..q{model.n}), got {len(row)}")
        try:
            data.append([float(x) for x in row[:model.n + 1]])
        except ValueError as exc:
            raise InputError(f"{p}, line {i}: not a number: {exc}") from exc
    arr = np.array(data)
    header = [h.strip() for h in rows[0]]
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

    def write_table(self, path: str | Path, quantity: str = "delta_p",
                    parameters: Sequence[str] | None = None,
                    xi_rows: Sequence[float] | None = None, *, overwrite: bool = False,
                    caption: str = "") -> Path:
        """Write :meth:`table` as CSV (``.csv``) or Markdown (``.md``)."""
        p = Path(path)
        if p.exists() and not overwrite:
            raise OutputExistsError(f"{p}: exists; pass overwrite=True (--force) to replace it")
        p.parent.mkdir(parents=True, exist_ok=True)
        header, rows = self.table(quantity, parameters, xi_rows)
        if p.suffix == ".csv":
            with p.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(header)
                for r in rows:
                    w.writerow([f"{r[0]:g}", *[f"{v:.6e}" for v in r[1:]]])
        else:
            lines = [caption, ""] if caption else []
            lines.append("| xi (%) | " + " | ".join(header[1:]) + " |")
            lines.append("|---:|" + "---:|" * (len(header) - 1))
            for r in rows:
                lines.append(f"| {r[0]:g} | " + " | ".join(f"{v:.2E}" for v in r[1:]) + " |")
            lines += ["", f"Sign convention: {self.convention}.", ""]
            p.write_text("\n".join(lines), encoding="utf-8")
        return p

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
    for i, nm in enumerate(names):
        for j, xi in enumerate(xis):
            pert = Perturbation({nm: xi}, sign_zero_links, sign_zero_axes)
            axes, bodies = pert.arrays(model)
            K.fk_pose_batch(q, np.ascontiguousarray(axes), np.ascontiguousarray(bodies), prism,
                            out)
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
