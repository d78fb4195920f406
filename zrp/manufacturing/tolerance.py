"""Tolerance analysis beyond the paper: Monte Carlo, first-order worst case, allocation.

Every geometric parameter of :mod:`zrp.manufacturing.sensitivity` (body-vector components
b{k}.x/y/z in the model's length unit, axis tilts u{k}.t1/t2 in rad, optionally joint offsets)
gets a tolerance ``tol_i``. A *robot* is one draw of all parameters:

* ``"uniform"``: dx_i ~ U(-tol_i, tol_i) (tol is the half-width);
* ``"normal"``: dx_i ~ N(0, (tol_i / 3)^2) (tol is three standard deviations).

Each robot follows the nominal joint trajectory q(t) (nominal inverse kinematics); its exact,
nonlinear deviations from the nominal arm give max_t delta_p (eq 17) and max_t theta_eps
(error angle; the paper's eq (15) value is 2 sqrt(2) sin(theta/2)). The Monte Carlo runs in a
compiled kernel (:mod:`zrp.manufacturing._mc_kernels`).

**Allocation.** :func:`allocate_tolerances` finds per-parameter tolerances that meet a
requirement such as "delta_p <= 0.1 mm at the 99th percentile of max_t delta_p" while keeping
them as loose as possible. *Looseness is scored with the reciprocal cost-tolerance model*:
manufacturing cost ``C = sum_i 1 / (c_i tol_i)``, where c_i = 1 for lengths (model unit) and
c_i = ``angle_scale_mm`` (default 100 mm) for angles, i.e. an angular tolerance counts like
the lateral tolerance it produces at 100 mm. The reported looseness is the harmonic mean of the
length-equivalent tolerances, ``H = P / C`` (larger is looser, i.e. cheaper). Minimising C under
a first-order root-sum-square constraint ``sum_i s_i^2 tol_i^2 = const`` gives
``tol_i ∝ (1 / (c_i s_i^2))^(1/3)`` (Lagrange), where s_i^2 is the trajectory-mean squared
sensitivity (normalised by the requirement). That shape is kept (capped at ``max_length`` /
``max_angle_rad``) and one common scale is found by bisection on the *nonlinear* Monte Carlo
percentile (common random numbers), then verified with fresh draws. The result is compared with
the equal-tolerance allocation (one length-equivalent tolerance for all) meeting the same
requirement.
"""

from __future__ import annotations

import fnmatch
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.errors import InputError, OutputExistsError
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.manufacturing import _mc_kernels as MK
from zrp.manufacturing.sensitivity import (
    Contribution,
    contributions,
    parameter_jacobian,
    parameter_space,
    perturbed_arrays,
    worst_case_bound,
)
from zrp.model.manipulator import Manipulator

__all__ = [
    "DISTRIBUTIONS",
    "Allocation",
    "MonteCarloResult",
    "Tolerances",
    "allocate_tolerances",
    "draw_parameters",
    "first_order_max",
    "monte_carlo",
    "percentile_ci",
    "tolerance_report",
]

F64 = NDArray[np.float64]
DISTRIBUTIONS = ("uniform", "normal")
DEFAULT_PERCENTILES = (50.0, 90.0, 95.0, 99.0, 99.9)


def _check_percentile(pct: float, name: str = "percentile") -> float:
    try:
        v = float(pct)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number in [0, 100], got {pct!r}") from exc
    if not 0.0 <= v <= 100.0:
        raise InputError(f"{name}: expected a number in [0, 100] (e.g. 99), got {pct!r}")
    return v


def _check_distribution(distribution: str) -> str:
    if distribution not in DISTRIBUTIONS:
        raise InputError(f"distribution: {distribution!r} is unknown; expected one of "
                         f"{DISTRIBUTIONS}")
    return distribution


def _positive_int(value: int, name: str, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def _nonneg(value: float, name: str, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {value!r}") from exc
    if not np.isfinite(v) or v < 0:
        raise InputError(f"{name}: expected a finite value >= 0 ({unit}), got {value!r}")
    return v


@dataclass(frozen=True, eq=False)
class Tolerances:
    """Per-parameter tolerances (half-width for "uniform", 3 sigma for "normal").

    Attributes:
        values: tol_i in parameter units, shape (P,), finite and >= 0.
        names: P parameter names (:func:`zrp.manufacturing.sensitivity.parameter_names` order).
        units: P units (length unit or "rad").
        joint_offsets: whether the joint-offset parameters are included.
    """

    values: F64
    names: tuple[str, ...]
    units: tuple[str, ...]
    joint_offsets: bool = False

    def __post_init__(self) -> None:
        vals = np.array(self.values, dtype=float)
        if vals.shape != (len(self.names),) or len(self.units) != len(self.names):
            raise InputError(f"Tolerances.values: expected shape ({len(self.names)},) matching "
                             f"the names and units, got {vals.shape}")
        bad = ~np.isfinite(vals) | (vals < 0)
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"tolerance of {self.names[i]}: expected a finite value >= 0 "
                             f"({self.units[i]}), got {vals[i]!r}")
        vals.setflags(write=False)
        object.__setattr__(self, "values", vals)

    @classmethod
    def build(cls, model: Manipulator, *, length: float = 0.0, angle_rad: float = 0.0,
              offset: float = 0.0, per_parameter: Mapping[str, float] | None = None,
              joint_offsets: bool = False) -> Tolerances:
        """Global tolerances with per-parameter overrides.

        Args:
            length: tolerance of every body-vector component (model length unit).
            angle_rad: tolerance of every axis tilt (rad).
            offset: tolerance of every joint offset (rad / length unit), if ``joint_offsets``.
            per_parameter: {name or glob pattern: tolerance}, applied in order after the
                globals, e.g. ``{"b1.*": 0, "u2.*": 2e-4}``. Names: ``b{k}.x|y|z``,
                ``u{k}.t1|t2``, ``q{k}.offset``.
        """
        space = parameter_space(model, joint_offsets=joint_offsets)
        length = _nonneg(length, "length", model.length_unit)
        angle_rad = _nonneg(angle_rad, "angle_rad", "rad")
        offset = _nonneg(offset, "offset", "rad or length unit")
        vals = np.where(np.array(space.kind) == "body", length,
                        np.where(np.array(space.kind) == "tilt", angle_rad, offset))
        for pattern, tol in (per_parameter or {}).items():
            hits = [i for i, nm in enumerate(space.names) if fnmatch.fnmatchcase(nm, pattern)]
            if not hits:
                raise InputError(
                    f"tolerance {pattern!r}: matches no parameter of {model.name!r}; expected a "
                    f"name or pattern such as b3.x, b3.*, u2.t1, u*.* (parameters: "
                    f"{space.names[0]} .. {space.names[-1]})")
            vals[hits] = _nonneg(tol, f"tolerance {pattern!r}", "parameter unit")
        return cls(vals, space.names, space.units, joint_offsets)

    def scaled(self, factor: float) -> Tolerances:
        return Tolerances(self.values * factor, self.names, self.units, self.joint_offsets)

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}

    def equivalent_mm(self, angle_scale_mm: float) -> F64:
        """Length-equivalent tolerances: angles times ``angle_scale_mm``, shape (P,)."""
        scale = np.where(np.array(self.units) == "rad", angle_scale_mm, 1.0)
        return self.values * scale

    def looseness(self, angle_scale_mm: float = 100.0) -> float:
        """Harmonic mean of the length-equivalent tolerances (0 if any is 0); see module doc."""
        eq = self.equivalent_mm(angle_scale_mm)
        if np.any(eq <= 0):
            return 0.0
        return float(eq.size / np.sum(1.0 / eq))


def draw_parameters(tolerances: Tolerances, n: int, distribution: str,
                    rng: np.random.Generator) -> F64:
    """Random parameter steps, shape (n, P): U(-tol, tol) or N(0, (tol/3)^2)."""
    _check_distribution(distribution)
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
                         f"got {type(rng).__name__}")
    p = tolerances.values.size
    if distribution == "uniform":
        z = rng.uniform(-1.0, 1.0, size=(n, p))
    else:
        z = rng.standard_normal(size=(n, p)) / 3.0
    return z * tolerances.values


def percentile_ci(samples: ArrayLike, pct: float, confidence: float = 0.95) -> tuple[float,
                                                                                       float]:
    """Distribution-free confidence interval of a percentile from order statistics.

    Uses the normal approximation of the binomial count below the percentile.
    """
    x = np.sort(np.asarray(samples, dtype=float))
    n = x.size
    p = pct / 100.0
    z = {0.9: 1.645, 0.95: 1.96, 0.99: 2.576}.get(confidence, 1.96)
    half = z * np.sqrt(n * p * (1 - p))
    lo = int(np.clip(np.floor(n * p - half), 0, n - 1))
    hi = int(np.clip(np.ceil(n * p + half), 0, n - 1))
    return float(x[lo]), float(x[hi])


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """Distribution of the per-robot maxima along the trajectory.

    Attributes:
        max_delta_p: max_t delta_p per robot (length unit), shape (N,).
        max_angle_rad: max_t theta_eps per robot (rad), shape (N,).
        first_order_delta_p, first_order_angle_rad: the same from the first-order model with the
            same draws, shape (N,), or None.
        tolerances: the tolerances used.
        distribution: "uniform" or "normal".
        n_points: trajectory points T.
        elapsed_s: wall time of the nonlinear kernel only (s).
        unit: length unit.
        seed_info: free text on the random generator.
    """

    max_delta_p: F64
    max_angle_rad: F64
    tolerances: Tolerances
    distribution: str
    n_points: int
    elapsed_s: float
    unit: str = "mm"
    first_order_delta_p: F64 | None = None
    first_order_angle_rad: F64 | None = None
    percentiles: tuple[float, ...] = field(default=DEFAULT_PERCENTILES)

    def __post_init__(self) -> None:
        n = np.shape(self.max_delta_p)
        if len(n) != 1 or np.shape(self.max_angle_rad) != n:
            raise InputError("MonteCarloResult: max_delta_p and max_angle_rad must have the "
                             "same shape (N,)")

    @property
    def n_robots(self) -> int:
        return int(self.max_delta_p.size)

    @property
    def max_delta_r(self) -> F64:
        """The paper's eq (15) value of max_t theta: 2 sqrt(2) sin(theta/2), shape (N,)."""
        return np.sqrt(8.0) * np.sin(0.5 * self.max_angle_rad)

    @property
    def poses_per_s(self) -> float:
        return self.n_robots * self.n_points / max(self.elapsed_s, 1e-12)

    def percentile(self, pct: float) -> tuple[float, float]:
        """(delta_p, angle_rad) percentiles of the per-robot maxima; 0 <= pct <= 100."""
        _check_percentile(pct)
        return (float(np.percentile(self.max_delta_p, pct)),
                float(np.percentile(self.max_angle_rad, pct)))

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "n_robots": self.n_robots, "n_points": self.n_points,
            "distribution": self.distribution,
            "tolerance_meaning": "half-width" if self.distribution == "uniform" else "3 sigma",
            "elapsed_s": self.elapsed_s, "poses_per_s": self.poses_per_s,
            "length_unit": self.unit,
            f"max_delta_p_{self.unit}": {}, "max_angle_rad": {}, "max_delta_R_eq15": {},
        }
        for pct in self.percentiles:
            dp, ang = self.percentile(pct)
            key = f"p{pct:g}"
            out[f"max_delta_p_{self.unit}"][key] = dp
            out["max_angle_rad"][key] = ang
            out["max_delta_R_eq15"][key] = float(np.sqrt(8.0) * np.sin(0.5 * ang))
        if self.first_order_delta_p is not None and self.first_order_angle_rad is not None:
            out["first_order"] = {
                f"max_delta_p_{self.unit}": {f"p{p:g}": float(np.percentile(
                    self.first_order_delta_p, p)) for p in self.percentiles},
                "max_angle_rad": {f"p{p:g}": float(np.percentile(
                    self.first_order_angle_rad, p)) for p in self.percentiles},
            }
        return out

    def histogram_png(self, path: str | Path, *, overwrite: bool = False,
                      title: str = "") -> Path:
        """Histograms of max_t delta_p and max_t theta with percentile markers."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        p = Path(path)
        if p.exists() and not overwrite:
            raise OutputExistsError(f"{p}: exists; pass overwrite=True (--force) to replace it")
        p.parent.mkdir(parents=True, exist_ok=True)
        fig, axs = plt.subplots(1, 2, figsize=(11, 4))
        for ax, data, label in ((axs[0], self.max_delta_p, f"max delta_p ({self.unit})"),
                                (axs[1], self.max_angle_rad * 1e3, "max error angle (mrad)")):
            ax.hist(data, bins=80, color="#4477aa", alpha=0.85)
            for pct, ls in ((50, ":"), (95, "--"), (99, "-")):
                v = np.percentile(data, pct)
                ax.axvline(v, color="#cc3311", ls=ls, label=f"P{pct} = {v:.4g}")
            ax.set_xlabel(label)
            ax.set_ylabel("robots")
            ax.legend()
        fig.suptitle(title or f"Monte Carlo, {self.n_robots} robots x {self.n_points} points, "
                     f"{self.distribution}")
        fig.tight_layout()
        fig.savefig(p, dpi=110)
        plt.close(fig)
        return p


def _trajectory_arrays(model: Manipulator, q: ArrayLike) -> tuple[F64, F64, F64, F64, F64]:
    q = check_q(model, q)
    if q.ndim != 2:
        raise InputError(f"q: expected a joint trajectory of shape (T, {model.n}), got {q.shape}")
    q = np.ascontiguousarray(q, dtype=float)
    pd, ed = end_effector_pose(model, q)
    return (q, np.ascontiguousarray(np.cos(0.5 * q)), np.ascontiguousarray(np.sin(0.5 * q)),
            np.ascontiguousarray(pd), np.ascontiguousarray(ed))


def _nonlinear_maxima(model: Manipulator, arrays: tuple[F64, F64, F64, F64, F64], dx: F64,
                      joint_offsets: bool) -> tuple[F64, F64]:
    q, ch, sh, pd, ed = arrays
    axes, bodies, off = perturbed_arrays(model, dx, joint_offsets=joint_offsets)
    n_r = dx.shape[0]
    out_dp = np.empty(n_r)
    out_s = np.empty(n_r)
    MK.mc_max_deviation(ch, sh, q, np.ascontiguousarray(axes), np.ascontiguousarray(bodies),
                        np.array(model.prismatic, dtype=np.bool_), np.ascontiguousarray(off),
                        bool(joint_offsets), pd, ed, out_dp, out_s)
    return out_dp, 2.0 * np.arcsin(np.minimum(out_s, 1.0))


def first_order_max(jac: ArrayLike, dx: ArrayLike, chunk: int = 2048) -> tuple[F64, F64]:
    """First-order per-robot maxima: max_t ||J_p(t) dx|| and max_t ||J_r(t) dx||.

    Args:
        jac: identification Jacobian along the trajectory, shape (T, 6, P).
        dx: parameter steps, shape (N, P).

    Returns:
        max delta_p (length unit) and max angle (rad), each shape (N,).
    """
    jac = np.asarray(jac, dtype=float)
    dx = np.asarray(dx, dtype=float)
    t_n, _, p = jac.shape
    flat = jac.reshape(t_n * 6, p).T  # (P, T*6)
    out_p = np.empty(dx.shape[0])
    out_r = np.empty(dx.shape[0])
    for i in range(0, dx.shape[0], chunk):
        y = (dx[i:i + chunk] @ flat).reshape(-1, t_n, 6)
        out_r[i:i + chunk] = np.linalg.norm(y[..., 0:3], axis=-1).max(axis=1)
        out_p[i:i + chunk] = np.linalg.norm(y[..., 3:6], axis=-1).max(axis=1)
    return out_p, out_r


def monte_carlo(model: Manipulator, q: ArrayLike, tolerances: Tolerances, n_robots: int, *,
                rng: np.random.Generator, distribution: str = "uniform",
                chunk: int = 8192, progress: bool = False, first_order: bool = False,
                percentiles: tuple[float, ...] = DEFAULT_PERCENTILES) -> MonteCarloResult:
    """Nonlinear Monte Carlo of N robots along the nominal joint trajectory.

    Args:
        model: the nominal arm.
        q: nominal inverse-kinematics joint values, shape (T, n).
        tolerances: from :meth:`Tolerances.build` for the same model.
        n_robots: N.
        rng: seeded generator, e.g. ``np.random.default_rng(1)``.
        distribution: "uniform" or "normal" (see the module docstring).
        chunk: robots per kernel call (progress-bar granularity).
        progress: show a tqdm progress bar.
        first_order: also evaluate the first-order model with the same draws.
    """
    _check_distribution(distribution)
    for pct in percentiles:
        _check_percentile(pct, "percentiles")
    n_robots = _positive_int(n_robots, "n_robots")
    chunk = _positive_int(chunk, "chunk")
    if not isinstance(tolerances, Tolerances):
        raise InputError(f"tolerances: expected a zrp.manufacturing.tolerance.Tolerances, got "
                         f"{type(tolerances).__name__}")
    space = parameter_space(model, joint_offsets=tolerances.joint_offsets)
    if space.names != tolerances.names:
        raise InputError(f"tolerances: built for another model (expected {space.size} parameters "
                         f"{space.names[0]}..{space.names[-1]}, got {len(tolerances.names)})")
    arrays = _trajectory_arrays(model, q)
    jac = parameter_jacobian(model, arrays[0], joint_offsets=tolerances.joint_offsets) \
        if first_order else None
    dp = np.empty(n_robots)
    ang = np.empty(n_robots)
    fo_p = np.empty(n_robots) if first_order else None
    fo_r = np.empty(n_robots) if first_order else None
    elapsed = 0.0
    from tqdm import tqdm

    with tqdm(total=n_robots, disable=not progress, unit="robot", desc="Monte Carlo") as bar:
        for i in range(0, n_robots, chunk):
            m = min(chunk, n_robots - i)
            dx = draw_parameters(tolerances, m, distribution, rng)
            t0 = time.perf_counter()
            dp[i:i + m], ang[i:i + m] = _nonlinear_maxima(model, arrays, dx,
                                                          tolerances.joint_offsets)
            elapsed += time.perf_counter() - t0
            if jac is not None and fo_p is not None and fo_r is not None:
                fo_p[i:i + m], fo_r[i:i + m] = first_order_max(jac, dx)
            bar.update(m)
    return MonteCarloResult(dp, ang, tolerances, distribution, int(arrays[0].shape[0]), elapsed,
                            model.length_unit, fo_p, fo_r, tuple(percentiles))


@dataclass(frozen=True, eq=False)
class Allocation:
    """Result of :func:`allocate_tolerances`.

    Attributes:
        tolerances: the allocated tolerances.
        baseline: the equal-length-equivalent tolerances meeting the same requirement.
        looseness_mm, baseline_looseness_mm: harmonic mean of length-equivalent tolerances.
        requirement: {"max_delta_p", "max_angle_rad", "percentile"} (None where not required).
        verification: Monte Carlo of the allocation with fresh draws.
        verified: whether the verification met the requirement.
        ci_delta_p: 95 % confidence interval of the verified delta_p percentile.
        angle_scale_mm: weight turning rad into length-equivalent mm.
        contribution: ranked first-order contributions under the allocated tolerances.
        worst_case_p, worst_case_angle_rad: first-order worst-case bounds (max over t).
        scale_rounds: number of verification rounds (1 if the first verification passed).
    """

    tolerances: Tolerances
    baseline: Tolerances
    looseness_mm: float
    baseline_looseness_mm: float
    requirement: dict[str, float | None]
    verification: MonteCarloResult
    verified: bool
    ci_delta_p: tuple[float, float]
    angle_scale_mm: float
    contribution: Contribution
    worst_case_p: float
    worst_case_angle_rad: float
    scale_rounds: int

    def __post_init__(self) -> None:
        if not isinstance(self.tolerances, Tolerances) or not isinstance(self.baseline,
                                                                          Tolerances):
            raise InputError("Allocation: tolerances and baseline must be Tolerances")
        if not isinstance(self.verification, MonteCarloResult):
            raise InputError("Allocation.verification: expected a MonteCarloResult")

    def summary(self) -> dict[str, Any]:
        pct = float(self.requirement["percentile"] or 99.0)
        dp, ang = self.verification.percentile(pct)
        return {
            "requirement": self.requirement,
            "looseness_score": "harmonic mean of length-equivalent tolerances (mm); angles "
                               f"count as tol_rad * {self.angle_scale_mm:g} mm",
            "looseness_mm": self.looseness_mm,
            "baseline_equal_tolerance_looseness_mm": self.baseline_looseness_mm,
            "looser_than_baseline_factor": self.looseness_mm / self.baseline_looseness_mm
            if self.baseline_looseness_mm > 0 else float("inf"),
            "verified": self.verified,
            f"verified_p{pct:g}_delta_p": dp,
            f"verified_p{pct:g}_delta_p_ci95": list(self.ci_delta_p),
            f"verified_p{pct:g}_angle_rad": ang,
            "verification_robots": self.verification.n_robots,
            "first_order_worst_case_delta_p": self.worst_case_p,
            "first_order_worst_case_angle_rad": self.worst_case_angle_rad,
            "tolerances": self.tolerances.as_dict(),
            "baseline_tolerances": self.baseline.as_dict(),
        }


def _scale_to_requirement(model: Manipulator, arrays: tuple[F64, F64, F64, F64, F64],
                          shape: F64, caps: F64, fixed: F64, free: NDArray[np.bool_], z: F64,
                          pct: float, req_p: float | None, req_r: float | None,
                          joint_offsets: bool, rel_tol: float = 1e-4) -> float:
    """Largest alpha with percentile(max(dp/req_p, ang/req_r)) <= 1, tol = min(alpha shape, cap)
    on the free parameters (bisection in log alpha on common random numbers ``z``)."""

    def ratio(alpha: float) -> float:
        tol = np.where(free, np.minimum(alpha * shape, caps), fixed)
        dp, ang = _nonlinear_maxima(model, arrays, z * tol, joint_offsets)
        r = 0.0
        if req_p is not None:
            r = max(r, float(np.percentile(dp, pct)) / req_p)
        if req_r is not None:
            r = max(r, float(np.percentile(ang, pct)) / req_r)
        return r

    r0 = ratio(0.0)
    if r0 > 1.0:
        raise InputError(f"the fixed tolerances alone violate the requirement (ratio {r0:.3g}); "
                         "loosen the requirement or tighten the fixed tolerances")
    lo, hi = 0.0, 1.0
    while ratio(hi) <= 1.0:
        lo, hi = hi, hi * 4.0
        if hi > 1e12:
            return hi  # every free tolerance sits at its cap
    if lo == 0.0:
        lo = hi
        while ratio(lo) > 1.0:
            hi, lo = lo, lo / 4.0
            if lo < 1e-18:
                raise InputError("allocation: the requirement cannot be met by any tolerance")
    for _ in range(40):
        mid = np.sqrt(lo * hi)
        if ratio(mid) <= 1.0:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.0 + rel_tol:
            break
    return lo


def allocate_tolerances(
    model: Manipulator,
    q: ArrayLike,
    *,
    rng: np.random.Generator,
    max_delta_p: float | None = 0.1,
    max_angle_rad: float | None = None,
    percentile: float = 99.0,
    distribution: str = "uniform",
    angle_scale_mm: float = 100.0,
    max_length: float = 1.0,
    max_tilt_rad: float = 0.01,
    fixed: Mapping[str, float] | None = None,
    n_search: int = 4000,
    n_verify: int = 20000,
    margin: float = 0.01,
    refine: bool = True,
    progress: bool = False,
) -> Allocation:
    """Loosest tolerances (reciprocal cost model, see the module docstring) meeting a
    percentile requirement along the trajectory, verified by a fresh nonlinear Monte Carlo.

    Args:
        q: nominal joint trajectory, shape (T, n).
        max_delta_p: requirement on max_t delta_p (length unit) at ``percentile``, or None.
        max_angle_rad: requirement on max_t theta_eps (rad) at ``percentile``, or None.
        percentile: e.g. 99 for "99 % of robots".
        angle_scale_mm: length-equivalent of 1 rad in the cost (default 100 mm).
        max_length, max_tilt_rad: caps on any allocated tolerance.
        fixed: {name or pattern: tolerance} kept as given (e.g. {"b1.*": 0}).
        n_search, n_verify: robots used by the bisection and by the verification.
        margin: the search aims at (1 - margin) times the requirement, to absorb the
            sampling noise of the verification.
        refine: also tune the split between length and angle tolerances (one factor on all
            body components, golden-section search in [1/4, 4] on the nonlinear percentile):
            the RSS shape is optimal within each kind only to first order.
    """
    if max_delta_p is None and max_angle_rad is None:
        raise InputError("requirement: give max_delta_p and/or max_angle_rad")
    req_p = None if max_delta_p is None else _nonneg(max_delta_p, "max_delta_p",
                                                     model.length_unit)
    req_r = None if max_angle_rad is None else _nonneg(max_angle_rad, "max_angle_rad", "rad")
    if (req_p is not None and req_p <= 0) or (req_r is not None and req_r <= 0):
        raise InputError("requirement: max_delta_p / max_angle_rad must be > 0")
    if not 0.0 < float(percentile) < 100.0:
        raise InputError(f"percentile: expected 0 < percentile < 100, got {percentile!r}")
    _check_distribution(distribution)
    angle_scale_mm = _nonneg(angle_scale_mm, "angle_scale_mm", "mm per rad")
    if angle_scale_mm <= 0:
        raise InputError("angle_scale_mm: expected > 0")
    if not 0.0 <= margin < 0.5:
        raise InputError(f"margin: expected 0 <= margin < 0.5, got {margin!r}")
    n_search = _positive_int(n_search, "n_search", 100)
    n_verify = _positive_int(n_verify, "n_verify", 100)

    space = parameter_space(model)
    arrays = _trajectory_arrays(model, q)
    jac = parameter_jacobian(model, arrays[0])
    is_ang = np.array(space.units) == "rad"
    c = np.where(is_ang, angle_scale_mm, 1.0)
    caps = np.where(is_ang, _nonneg(max_tilt_rad, "max_tilt_rad", "rad"),
                    _nonneg(max_length, "max_length", model.length_unit))
    fixed_tol = Tolerances.build(model, per_parameter=fixed or {}) if fixed else None
    free = np.ones(space.size, dtype=bool)
    fixed_vals = np.zeros(space.size)
    if fixed_tol is not None:
        for pattern in fixed or {}:
            for i, nm in enumerate(space.names):
                if fnmatch.fnmatchcase(nm, pattern):
                    free[i] = False
        fixed_vals = np.where(free, 0.0, fixed_tol.values)
    # first-order sensitivities, normalised by the requirement
    s2 = np.zeros(space.size)
    if req_p is not None:
        s2 += np.mean(np.sum(jac[:, 3:6, :] ** 2, axis=1), axis=0) / req_p**2
    if req_r is not None:
        s2 += np.mean(np.sum(jac[:, 0:3, :] ** 2, axis=1), axis=0) / req_r**2
    with np.errstate(divide="ignore"):
        shape = np.where(s2 > 0, (1.0 / (c * np.where(s2 > 0, s2, 1.0))) ** (1.0 / 3.0), np.inf)
    shape = np.where(np.isfinite(shape), shape, caps * 1e6)
    pct = float(percentile)
    z = draw_parameters(Tolerances(np.ones(space.size), space.names, space.units), n_search,
                        distribution, rng)
    target_p = None if req_p is None else req_p * (1 - margin)
    target_r = None if req_r is None else req_r * (1 - margin)
    alpha = _scale_to_requirement(model, arrays, shape, caps, fixed_vals, free, z, pct,
                                  target_p, target_r, False)
    if refine and is_ang.any() and (~is_ang).any():
        def score(log_g: float) -> tuple[float, float, F64]:
            sh = shape * np.where(is_ang, 1.0, np.exp(log_g))
            a = _scale_to_requirement(model, arrays, sh, caps, fixed_vals, free, z, pct,
                                      target_p, target_r, False, rel_tol=1e-3)
            tol_g = Tolerances(np.where(free, np.minimum(a * sh, caps), fixed_vals),
                               space.names, space.units)
            return tol_g.looseness(angle_scale_mm), a, sh

        best = (Tolerances(np.where(free, np.minimum(alpha * shape, caps), fixed_vals),
                           space.names, space.units).looseness(angle_scale_mm), alpha, shape)
        lo_g, hi_g = np.log(0.25), np.log(4.0)
        gr = (np.sqrt(5.0) - 1.0) / 2.0
        x1, x2 = hi_g - gr * (hi_g - lo_g), lo_g + gr * (hi_g - lo_g)
        f1, f2 = score(x1), score(x2)
        for _ in range(8):
            if f1[0] >= f2[0]:
                hi_g, x2, f2 = x2, x1, f1
                x1 = hi_g - gr * (hi_g - lo_g)
                f1 = score(x1)
            else:
                lo_g, x1, f1 = x1, x2, f2
                x2 = lo_g + gr * (hi_g - lo_g)
                f2 = score(x2)
        for cand in (f1, f2):
            if cand[0] > best[0]:
                best = cand
        _, alpha, shape = best
    equal_shape = 1.0 / c
    beta = _scale_to_requirement(model, arrays, equal_shape, caps, fixed_vals, free, z, pct,
                                 target_p, target_r, False)
    base = Tolerances(np.where(free, np.minimum(beta * equal_shape, caps), fixed_vals),
                      space.names, space.units)

    rounds = 0
    while True:
        rounds += 1
        tol = Tolerances(np.where(free, np.minimum(alpha * shape, caps), fixed_vals),
                         space.names, space.units)
        ver = monte_carlo(model, arrays[0], tol, n_verify, rng=rng, distribution=distribution,
                          progress=progress)
        dp, ang = ver.percentile(pct)
        r = max(dp / req_p if req_p else 0.0, ang / req_r if req_r else 0.0)
        if r <= 1.0 or rounds >= 6:
            break
        alpha *= 0.99 / r
    wc_p, wc_r = worst_case_bound(jac, tol.values)
    var_factor = 1.0 / 3.0 if distribution == "uniform" else 1.0 / 9.0
    contrib = contributions(jac, tol.values, space.names, space.units,
                            variance_factor=var_factor)
    return Allocation(
        tolerances=tol, baseline=base, looseness_mm=tol.looseness(angle_scale_mm),
        baseline_looseness_mm=base.looseness(angle_scale_mm),
        requirement={"max_delta_p": req_p, "max_angle_rad": req_r, "percentile": pct},
        verification=ver, verified=bool(r <= 1.0),
        ci_delta_p=percentile_ci(ver.max_delta_p, pct), angle_scale_mm=angle_scale_mm,
        contribution=contrib, worst_case_p=float(wc_p.max()),
        worst_case_angle_rad=float(wc_r.max()), scale_rounds=rounds)


def tolerance_report(model: Manipulator, q: ArrayLike, tolerances: Tolerances,
                     mc: MonteCarloResult | None = None) -> dict[str, Any]:
    """First-order analysis of given tolerances: contributions, worst case, and (if ``mc`` is
    given) its comparison with the Monte Carlo maxima."""
    q = check_q(model, q)
    jac = parameter_jacobian(model, q, joint_offsets=tolerances.joint_offsets)
    dist = mc.distribution if mc is not None else "uniform"
    var_factor = 1.0 / 3.0 if dist == "uniform" else 1.0 / 9.0
    contrib = contributions(jac, tolerances.values, tolerances.names, tolerances.units,
                            variance_factor=var_factor)
    wc_p, wc_r = worst_case_bound(jac, tolerances.values)
    out: dict[str, Any] = {
        "worst_case_delta_p": float(wc_p.max()),
        "worst_case_angle_rad": float(wc_r.max()),
        "worst_case_t_index": int(np.argmax(wc_p)),
        "contribution": contrib,
    }
    if mc is not None:
        out["mc_max_delta_p"] = float(mc.max_delta_p.max())
        out["mc_max_angle_rad"] = float(mc.max_angle_rad.max())
        out["mc_over_worst_case_p"] = float(mc.max_delta_p.max() / wc_p.max()) \
            if wc_p.max() > 0 else 0.0
    return out
