"""A population of manufactured robots: nonlinear Monte Carlo along a nominal trajectory.

Each robot (one :func:`~zrp.manufacturing.tolerance.draw_parameters` draw) follows the nominal
joint trajectory q(t) (nominal inverse kinematics); its exact, nonlinear deviations from the
nominal arm give max_t delta_p (eq 17) and max_t theta_eps (error angle; the paper's eq (15)
value is 2 sqrt(2) sin(theta/2)). The Monte Carlo runs in a compiled kernel
(:mod:`zrp.manufacturing._mc_kernels`); :func:`first_order_max` gives the first-order model's
maxima for the same draws. Histograms: :func:`zrp.manufacturing.plots.histogram_png`.
"""

from __future__ import annotations

from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.identification import parameter_space
from zrp.manufacturing._checks import check_distribution, check_percentile, positive_int
from zrp.manufacturing.chunks import ChunkResult, ChunkTask, chunk_size, run_chunk
from zrp.manufacturing.maxima import first_order_max as first_order_max
from zrp.manufacturing.maxima import nonlinear_maxima as nonlinear_maxima
from zrp.manufacturing.maxima import trajectory_arrays as trajectory_arrays
from zrp.manufacturing.tolerance import Tolerances, draw_parameters, percentile_ci
from zrp.model.manipulator import Manipulator
from zrp.tasks import map_tasks

__all__ = [
    "DEFAULT_PERCENTILES",
    "MonteCarloResult",
    "chunk_tasks",
    "first_order_max",
    "gather_chunks",
    "monte_carlo",
    "nonlinear_maxima",
    "trajectory_arrays",
]

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

    def maxima(self) -> tuple[float, float]:
        """The largest max_t delta_p and max_t theta over the robots."""
        return float(self.max_delta_p.max()), float(self.max_angle_rad.max())

    def percentile_ci(self, pct: float, confidence: float = 0.95) -> tuple[float, float]:
        """Distribution-free ``confidence`` interval of the ``pct`` percentile of
        max_t delta_p (:func:`~zrp.manufacturing.tolerance.percentile_ci`)."""
        return percentile_ci(self.max_delta_p, pct, confidence)

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


def _check_tolerances(model: Manipulator, tolerances: Tolerances) -> None:
    if not isinstance(tolerances, Tolerances):
        raise InputError(f"tolerances: expected a zrp.manufacturing.tolerance.Tolerances, got "
                         f"{type(tolerances).__name__}")
    space = parameter_space(model, joint_offsets=tolerances.joint_offsets)
    if space.names != tolerances.names:
        raise InputError(f"tolerances: built for another model (expected {space.size} parameters "
                         f"{space.names[0]}..{space.names[-1]}, got {len(tolerances.names)})")


def _seed_or_rng(rng: np.random.Generator | None, seed: int | None) -> None:
    if (rng is None) == (seed is None):
        raise InputError("rng, seed: give exactly one (rng: draws here, in order; seed: each "
                         "chunk draws its own robots, for executors and clusters)")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))
                             or seed < 0):
        raise InputError(f"seed: expected an integer >= 0, got {seed!r}")


def chunk_tasks(model: Manipulator, q: ArrayLike, tolerances: Tolerances, n_robots: int, *,
                rng: np.random.Generator | None = None, seed: int | None = None,
                distribution: str = "uniform", chunk: int | None = None,
                first_order: bool = False,
                edges: tuple[F64, F64] | None = None) -> list[ChunkTask]:
    """The chunks of :func:`monte_carlo` (same arguments), for an application that maps
    :func:`~zrp.manufacturing.chunks.run_chunk` itself (checkpointing, its own scheduler);
    ``edges``: reduce each chunk on its worker (:mod:`zrp.manufacturing.reduction`)."""
    check_distribution(distribution)
    n_robots = positive_int(n_robots, "n_robots")
    if chunk is not None:
        chunk = positive_int(chunk, "chunk")
    _seed_or_rng(rng, seed)
    _check_tolerances(model, tolerances)
    arrays = trajectory_arrays(model, q)
    if chunk is None:  # from the work only: the same chunks for any executor
        chunk = chunk_size(n_robots, arrays[0].shape[0])
    tasks = []
    for idx, start in enumerate(range(0, n_robots, chunk)):
        m = min(chunk, n_robots - start)
        dx = None if rng is None else draw_parameters(tolerances, m, distribution, rng)
        tasks.append(ChunkTask(idx, start, m, model, arrays, tolerances, distribution,
                               None if seed is None else int(seed), dx, bool(first_order),
                               edges))
    return tasks


def gather_chunks(model: Manipulator, tasks: list[ChunkTask], results: list[ChunkResult],
                  percentiles: tuple[float, ...] = DEFAULT_PERCENTILES) -> MonteCarloResult:
    """One :class:`MonteCarloResult` from every chunk's result (in any order)."""
    by_index = {r.index: r for r in results}
    missing = [t.index for t in tasks if t.index not in by_index]
    if missing:
        raise InputError(f"results: chunks {missing[:5]} are missing")
    ordered = [by_index[t.index] for t in tasks]
    if any(r.max_delta_p is None for r in ordered):
        raise InputError("results: the chunks were reduced on the workers (edges given); "
                         "merge their histograms (zrp.manufacturing.reduction)")
    cat = np.concatenate
    first = tasks[0].first_order
    return MonteCarloResult(
        cat([r.max_delta_p for r in ordered]), cat([r.max_angle_rad for r in ordered]),
        tasks[0].tolerances, tasks[0].distribution, int(tasks[0].arrays[0].shape[0]),
        float(sum(r.elapsed_s for r in ordered)), model.length_unit,
        cat([r.first_order_delta_p for r in ordered]) if first else None,
        cat([r.first_order_angle_rad for r in ordered]) if first else None,
        tuple(percentiles))


def monte_carlo(model: Manipulator, q: ArrayLike, tolerances: Tolerances, n_robots: int, *,
                rng: np.random.Generator | None = None, seed: int | None = None,
                distribution: str = "uniform", chunk: int | None = None,
                progress: bool = False,
                first_order: bool = False,
                percentiles: tuple[float, ...] = DEFAULT_PERCENTILES,
                executor: Executor | Any | None = None) -> MonteCarloResult:
    """Nonlinear Monte Carlo of N robots along the nominal joint trajectory.

    Args:
        model: the nominal arm.
        q: nominal inverse-kinematics joint values, shape (T, n).
        tolerances: from :meth:`Tolerances.build` for the same model.
        n_robots: N.
        rng: seeded generator, e.g. ``np.random.default_rng(1)``: the robots are drawn here,
            in order, and shipped to the executor; or
        seed: master seed: chunk i draws its own robots (:func:`~.chunks.chunk_rng`), so
            nothing but the seed travels (give exactly one of ``rng`` and ``seed``).
        distribution: "uniform" or "normal" (see the module docstring).
        chunk: robots per task (the seeded draws depend on it; the result never depends on
            the executor or its number of workers); None: chosen from the work
            (:func:`~.chunks.chunk_size`: tasks of ~1e7 poses, a multiple of 4 of them).
        progress: show a tqdm progress bar (advanced as chunks finish, also on a cluster).
        first_order: also evaluate the first-order model with the same draws.
        executor: None (this process; the kernel uses numba's threads) or any
            ``concurrent.futures``-style executor, e.g. a Dask ``Client.get_executor()``.

    ``elapsed_s`` of the result sums the kernel time of every chunk (CPU-seconds on the
    workers, not wall time).
    """
    for pct in percentiles:
        check_percentile(pct, "percentiles")
    tasks = chunk_tasks(model, q, tolerances, n_robots, rng=rng, seed=seed,
                        distribution=distribution, chunk=chunk, first_order=first_order)
    from tqdm import tqdm

    results: list[ChunkResult] = []
    with tqdm(total=n_robots, disable=not progress, unit="robot", desc="Monte Carlo") as bar:
        for i, res in map_tasks(run_chunk, tasks, executor):
            assert isinstance(res, ChunkResult)  # without capture, a failed chunk raises
            results.append(res)
            bar.update(tasks[i].size)
    return gather_chunks(model, tasks, results, tuple(percentiles))
