"""Chunked Monte Carlo: the unit of work a process pool or a cluster runs.

A Monte Carlo of N robots is cut into chunks of ``chunk`` robots (the last one shorter). Each
chunk is one :class:`ChunkTask` and :func:`run_chunk` evaluates it anywhere (this process, a
``concurrent.futures`` executor, a Dask ``Client.get_executor()``): the result depends only on
the task, never on where or in which order it ran, so any number of workers gives the same
robots bit for bit. Two ways of drawing the robots:

* ``dx`` given: the caller drew the parameter steps (from its ``rng``, in chunk order) and
  ships them (N x P x 8 bytes: fine up to ~1e7 robots);
* ``seed`` given: chunk i draws its own robots from
  ``np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))``; only the seed and
  the index travel, so 1e9 robots shard over any cluster. The draws depend on ``chunk``
  (by default :func:`chunk_size` chooses it from the work alone, never from the workers).

The chunks are mapped by :func:`zrp.tasks.map_tasks` (any ``concurrent.futures``-style
executor, or none).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.identification import parameter_jacobian
from zrp.manufacturing.histogram import Histogram
from zrp.manufacturing.maxima import first_order_max, nonlinear_maxima
from zrp.manufacturing.tolerance import Tolerances, draw_parameters
from zrp.model.manipulator import Manipulator

__all__ = ["MAX_CHUNK", "TASK_POSES", "ChunkResult", "ChunkTask", "chunk_rng", "chunk_size",
           "run_chunk"]



#: Poses (robots x trajectory points) per task when the chunk is chosen from the work: ~0.15 s
#: of kernel time on one core (~60 M poses/s), so a task's fixed cost on a Dask cluster (~2-5 ms:
#: scheduling, transfer, the worker's bookkeeping) stays a few per cent of it.
TASK_POSES = 10_000_000
#: At most this many robots a task (short paths): ~50 MB of draws and arrays on a worker.
MAX_CHUNK = 131_072


def chunk_size(n_robots: int, n_points: int) -> int:
    """Robots per task chosen from the work alone (never from the executor, so the seeded
    draws, which depend on the chunk, are the same for any number of workers).

    The number of tasks is ``ceil(n_robots * n_points / TASK_POSES)`` rounded up to a multiple
    of 4, and the robots are shared equally among them: the tasks then split evenly over 1, 2
    and 4 workers (no worker waits for the last task of another). 1e5 robots x 360 points ->
    4 tasks of 25,000 robots; 1e9 x 360 -> 36,000 tasks of 27,778; never more than
    :data:`MAX_CHUNK` robots a task.
    """
    if n_robots < 1 or n_points < 1:
        raise InputError(f"chunk_size: expected n_robots, n_points >= 1, got {n_robots}, "
                         f"{n_points}")
    tasks = -(-n_robots * n_points // TASK_POSES)
    tasks = min(n_robots, 4 * -(-tasks // 4))
    return min(-(-n_robots // tasks), MAX_CHUNK)


def chunk_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of chunk ``index`` of a seeded Monte Carlo (independent streams)."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(index),)))


@dataclass(frozen=True, eq=False)
class ChunkTask:
    """One chunk of a Monte Carlo (picklable; sent to a worker as is).

    Attributes:
        index: chunk number (0-based); robots ``start .. start + size - 1``.
        start, size: first robot and number of robots.
        model: the nominal arm.
        arrays: :func:`~zrp.manufacturing.population.trajectory_arrays` of the nominal path.
        tolerances, distribution: what the robots are drawn from.
        seed: master seed (draw on the worker), or None when ``dx`` is given.
        dx: parameter steps drawn by the caller, shape (size, P), or None.
        first_order: also the first-order maxima (the worker computes the identification
            Jacobian, ~30 ms, rather than receive its T x 6 x P x 8 bytes with every chunk).
        edges: bin edges (delta_p, angle) to reduce the chunk on the worker to two
            :class:`~zrp.manufacturing.histogram.Histogram` (four with ``first_order``: the
            first-order maxima over the same edges; a few KB whatever its size) instead of
            returning per-robot maxima; None returns the maxima.
    """

    index: int
    start: int
    size: int
    model: Manipulator
    arrays: tuple[F64, F64, F64, F64, F64]
    tolerances: Tolerances
    distribution: str
    seed: int | None = None
    dx: F64 | None = None
    first_order: bool = False
    edges: tuple[F64, F64] | None = None

    def __post_init__(self) -> None:
        if (self.seed is None) == (self.dx is None):
            raise InputError("ChunkTask: give exactly one of seed and dx")
        if self.dx is not None and self.dx.shape[0] != self.size:
            raise InputError(f"ChunkTask.dx: expected {self.size} rows, got {self.dx.shape[0]}")

    def draws(self) -> F64:
        """The chunk's parameter steps, shape (size, P)."""
        if self.dx is not None:
            return self.dx
        assert self.seed is not None
        return draw_parameters(self.tolerances, self.size, self.distribution,
                               chunk_rng(self.seed, self.index))


@dataclass(frozen=True, eq=False)
class ChunkResult:
    """Per-robot maxima of one chunk, each shape (size,) (None when reduced on the worker);
    first-order ones or None; ``elapsed_s``: wall time of the nonlinear kernel on the worker;
    ``histograms``: (delta_p, angle) histograms when the task gave ``edges``, followed by the
    first-order (delta_p, angle) ones when it also asked for ``first_order``; else None."""

    index: int
    max_delta_p: F64 | None
    max_angle_rad: F64 | None
    first_order_delta_p: F64 | None
    first_order_angle_rad: F64 | None
    elapsed_s: float
    histograms: tuple[Histogram, Histogram] | None = None


_JAC_CACHE: dict[bytes, F64] = {}


def _jacobian(task: ChunkTask) -> F64:
    """The identification Jacobian of the task's path, computed once per process and path."""
    m = task.model
    key = b"|".join([task.arrays[0].tobytes(), m.axes.tobytes(), m.bodies.tobytes(),
                     np.asarray(m.prismatic).tobytes(),
                     bytes([task.tolerances.joint_offsets])])
    jac = _JAC_CACHE.get(key)
    if jac is None:
        jac = parameter_jacobian(m, task.arrays[0], joint_offsets=task.tolerances.joint_offsets)
        _JAC_CACHE.clear()  # one path at a time: a run's chunks share it
        _JAC_CACHE[key] = jac
    return jac


def run_chunk(task: ChunkTask) -> ChunkResult:
    """Evaluate one chunk (wherever it runs)."""
    dx = task.draws()
    t0 = time.perf_counter()
    dp, ang = nonlinear_maxima(task.model, task.arrays, dx, task.tolerances.joint_offsets)
    elapsed = time.perf_counter() - t0
    fo_p = fo_r = None
    if task.first_order:
        fo_p, fo_r = first_order_max(_jacobian(task), dx)
    if task.edges is not None:  # reduce here: only the histograms travel back
        e_p, e_r = task.edges
        hists = (Histogram.of(dp, e_p), Histogram.of(ang, e_r))
        if fo_p is not None and fo_r is not None:
            hists += (Histogram.of(fo_p, e_p), Histogram.of(fo_r, e_r))
        return ChunkResult(task.index, None, None, None, None, elapsed, hists)
    return ChunkResult(task.index, dp, ang, fo_p, fo_r, elapsed)
