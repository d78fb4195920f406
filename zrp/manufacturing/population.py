"""A population of manufactured robots: nonlinear Monte Carlo along a nominal trajectory.

Each robot (one :func:`~zrp.manufacturing.tolerance.draw_parameters` draw) follows the nominal
joint trajectory q(t) (nominal inverse kinematics); its exact, nonlinear deviations from the
nominal arm give max_t delta_p (eq 17) and max_t theta_eps (error angle; the paper's eq (15)
value is 2 sqrt(2) sin(theta/2)). The Monte Carlo runs in a compiled kernel
(:mod:`zrp.manufacturing._mc_kernels`); :func:`first_order_max` gives the first-order model's
maxima for the same draws. Histograms: :func:`zrp.manufacturing.plots.histogram_png`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.errors import InputError
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.manufacturing import _mc_kernels as MK
from zrp.manufacturing._checks import check_distribution, check_percentile, positive_int
from zrp.manufacturing.sensitivity import parameter_jacobian, parameter_space, perturbed_arrays
from zrp.manufacturing.tolerance import Tolerances, draw_parameters
from zrp.model.manipulator import Manipulator

__all__ = [
    "DEFAULT_PERCENTILES",
    "MonteCarloResult",
    "first_order_max",
    "monte_carlo",
    "nonlinear_maxima",
    "trajectory_arrays",
]

F64 = NDArray[np.float64]
#: Percentiles a :class:`MonteCarloResult` summary reports by default.
DEFAULT_PERCENTILES = (50.0, 90.0, 95.0, 99.0, 99.9)


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
        check_percentile(pct)
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


def trajectory_arrays(model: Manipulator, q: ArrayLike) -> tuple[F64, F64, F64, F64, F64]:
    """The Monte Carlo kernel's view of a nominal joint trajectory q, shape (T, n):
    (q, cos(q/2), sin(q/2), nominal p, nominal E), each C-contiguous."""
    q = check_q(model, q)
    if q.ndim != 2:
        raise InputError(f"q: expected a joint trajectory of shape (T, {model.n}), got {q.shape}")
    q = np.ascontiguousarray(q, dtype=float)
    pd, ed = end_effector_pose(model, q)
    return (q, np.ascontiguousarray(np.cos(0.5 * q)), np.ascontiguousarray(np.sin(0.5 * q)),
            np.ascontiguousarray(pd), np.ascontiguousarray(ed))


def nonlinear_maxima(model: Manipulator, arrays: tuple[F64, F64, F64, F64, F64], dx: F64,
                     joint_offsets: bool) -> tuple[F64, F64]:
    """Exact per-robot maxima along the trajectory for parameter steps ``dx`` (N, P):
    max_t delta_p (length unit) and max_t error angle (rad), each shape (N,)."""
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
    check_distribution(distribution)
    for pct in percentiles:
        check_percentile(pct, "percentiles")
    n_robots = positive_int(n_robots, "n_robots")
    chunk = positive_int(chunk, "chunk")
    if not isinstance(tolerances, Tolerances):
        raise InputError(f"tolerances: expected a zrp.manufacturing.tolerance.Tolerances, got "
                         f"{type(tolerances).__name__}")
    space = parameter_space(model, joint_offsets=tolerances.joint_offsets)
    if space.names != tolerances.names:
        raise InputError(f"tolerances: built for another model (expected {space.size} parameters "
                         f"{space.names[0]}..{space.names[-1]}, got {len(tolerances.names)})")
    arrays = trajectory_arrays(model, q)
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
            dp[i:i + m], ang[i:i + m] = nonlinear_maxima(model, arrays, dx,
                                                          tolerances.joint_offsets)
            elapsed += time.perf_counter() - t0
            if jac is not None and fo_p is not None and fo_r is not None:
                fo_p[i:i + m], fo_r[i:i + m] = first_order_max(jac, dx)
            bar.update(m)
    return MonteCarloResult(dp, ang, tolerances, distribution, int(arrays[0].shape[0]), elapsed,
                            model.length_unit, fo_p, fo_r, tuple(percentiles))
