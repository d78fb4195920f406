"""Monte Carlo of any size: each chunk is reduced on its worker to two fixed-bin histograms
(max delta_p and max error angle per robot), merged here as they arrive.

:func:`~zrp.manufacturing.population.monte_carlo` gathers every robot's maxima (16 bytes a
robot: 1.6 GB for 1e8 robots, 16 GB for 1e9, more than a client holds). :func:`monte_carlo_summary`
returns the same distribution as a :class:`MonteCarloSummary`: whatever the number of robots
in a chunk, it sends back two histograms of ~33 KB each (counts and edges), and the client keeps
one merged pair. That is a reduction once a chunk holds more than ~4,000 robots (16 bytes
each): use large chunks for large runs (131,072 robots: 2 MB of maxima -> 66 KB). The edges
are fixed before the run from the first-order worst case of the tolerance box
(:func:`~zrp.manufacturing.budget.worst_case_bound`, B = 2048 geometric bins from 1e-4 to 10
times it, i.e. a relative bin width of 0.56 %; robots outside land in an underflow or overflow
bin, bracketed by the exact minimum or maximum); the count, the extremes, the mean and the
standard deviation are exact, a percentile is known to its bin (:meth:`Histogram.percentile`).
Same seed and chunk size as :func:`monte_carlo`: the same robots, so every percentile of the
full result lies in the bracket the summary gives (tested).
"""

from __future__ import annotations

import os
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arguments import check_float
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.identification import parameter_jacobian
from zrp.manufacturing._checks import check_percentile
from zrp.manufacturing.budget import worst_case_bound
from zrp.manufacturing.checkpoint import OrderedMerge, load_merge, run_identity, save_merge
from zrp.manufacturing.chunks import ChunkResult, ChunkTask, run_chunk
from zrp.manufacturing.histogram import Histogram, geometric_edges
from zrp.manufacturing.population import DEFAULT_PERCENTILES, chunk_tasks
from zrp.manufacturing.tolerance import Tolerances, percentile_ci_ranks
from zrp.model.manipulator import Manipulator
from zrp.tasks import map_tasks

__all__ = ["BINS", "MonteCarloSummary", "histogram_edges", "monte_carlo_summary"]

#: Bins per histogram and their span relative to the first-order worst case.
BINS = 2048
SPAN = (1e-4, 1e1)


def histogram_edges(model: Manipulator, q: ArrayLike, tolerances: Tolerances,
                    bins: int = BINS) -> tuple[F64, F64]:
    """Edges for max delta_p (length unit) and max angle (rad), each shape (bins + 1,):
    geometric over SPAN times the first-order worst case along q (shape (T, n))."""
    jac = parameter_jacobian(model, q, joint_offsets=tolerances.joint_offsets)
    wc_p, wc_r = worst_case_bound(jac, tolerances.values)
    out = []
    for wc in (float(np.max(wc_p)), float(np.max(wc_r))):
        ref = wc if wc > 0 else 1e-12  # zero tolerances: every robot is in the underflow bin
        out.append(geometric_edges(SPAN[0] * ref, SPAN[1] * ref, bins))
    return out[0], out[1]


@dataclass(frozen=True, eq=False)
class MonteCarloSummary:
    """The distribution of the per-robot maxima of a reduced Monte Carlo.

    Attributes:
        delta_p: histogram of max_t delta_p (length unit).
        angle_rad: histogram of max_t theta_eps (rad).
        tolerances, distribution, n_points, elapsed_s, unit, percentiles: as in
            :class:`~zrp.manufacturing.population.MonteCarloResult`.
        first_order_delta_p, first_order_angle_rad: histograms of the first-order model's
            maxima for the same robots (same edges), or None.
        resumed_robots: robots taken from a checkpoint rather than run now.
    """

    delta_p: Histogram
    angle_rad: Histogram
    tolerances: Tolerances
    distribution: str
    n_points: int
    elapsed_s: float
    unit: str = "mm"
    percentiles: tuple[float, ...] = field(default=DEFAULT_PERCENTILES)
    first_order_delta_p: Histogram | None = None
    first_order_angle_rad: Histogram | None = None
    resumed_robots: int = 0

    def __post_init__(self) -> None:
        if self.delta_p.total != self.angle_rad.total:
            raise InputError("MonteCarloSummary: delta_p and angle_rad count different robots")
        fo = (self.first_order_delta_p, self.first_order_angle_rad)
        if (fo[0] is None) != (fo[1] is None) or any(
                h is not None and h.total != self.delta_p.total for h in fo):
            raise InputError("MonteCarloSummary: first_order_delta_p and first_order_angle_rad"
                             " must both be given, for the same robots, or neither")
        for pct in self.percentiles:
            check_percentile(pct, "percentiles")

    @property
    def n_robots(self) -> int:
        return self.delta_p.total

    def percentile(self, pct: float) -> tuple[float, float]:
        """(delta_p, angle_rad) percentile estimates (each within its bin's bracket)."""
        return self.delta_p.percentile(pct)[0], self.angle_rad.percentile(pct)[0]

    @property
    def poses_per_s(self) -> float:
        return self.n_robots * self.n_points / max(self.elapsed_s, 1e-12)

    def maxima(self) -> tuple[float, float]:
        """The largest max_t delta_p and max_t theta over the robots (exact)."""
        return self.delta_p.maximum, self.angle_rad.maximum

    def percentile_ci(self, pct: float, confidence: float = 0.95) -> tuple[float, float]:
        """A conservative distribution-free ``confidence`` interval of the ``pct`` percentile
        of max_t delta_p: the order statistics of
        :func:`~zrp.manufacturing.tolerance.percentile_ci_ranks` are known to their bins, so
        the interval runs from the lower end of the first one's bin to the upper end of the
        second one's (it contains the interval the gathered robots give)."""
        lo, hi = percentile_ci_ranks(self.n_robots, pct, confidence)
        return self.delta_p.order_statistic(lo)[0], self.delta_p.order_statistic(hi)[1]

    def summary(self) -> dict[str, Any]:
        u = self.unit
        out: dict[str, Any] = {
            "n_robots": self.n_robots, "n_points": self.n_points,
            "distribution": self.distribution, "elapsed_s": self.elapsed_s,
            "reduced_on_workers": True, "resumed_robots": self.resumed_robots,
            "relative_bin_width": self.delta_p.relative_width,
            f"max_delta_p_{u}": {"max": self.delta_p.maximum, "mean": self.delta_p.mean},
            "max_angle_rad": {"max": self.angle_rad.maximum, "mean": self.angle_rad.mean},
        }
        blocks = [(out, f"max_delta_p_{u}", self.delta_p), (out, "max_angle_rad", self.angle_rad)]
        if self.first_order_delta_p is not None and self.first_order_angle_rad is not None:
            fo: dict[str, Any] = {f"max_delta_p_{u}": {}, "max_angle_rad": {}}
            out["first_order"] = fo
            blocks += [(fo, f"max_delta_p_{u}", self.first_order_delta_p),
                       (fo, "max_angle_rad", self.first_order_angle_rad)]
        for pct in self.percentiles:
            key = f"p{pct:g}"
            for parent, name, h in blocks:
                est, lo, hi = h.percentile(pct)
                parent[name][key] = est
                parent[name][f"{key}_bracket"] = [lo, hi]
        return out


@dataclass
class _Checkpoint:
    """Where and how often the merge state is saved (``path`` None: never)."""

    path: str | os.PathLike[str] | None
    identity: dict[str, str]
    every_s: float
    last: float = field(default_factory=time.monotonic)

    def save(self, state: OrderedMerge, *, now: bool = False) -> None:
        """Save the state when ``now`` or when ``every_s`` seconds have passed since the last
        save."""
        if self.path is None:
            return
        if now or time.monotonic() - self.last >= self.every_s:
            save_merge(self.path, self.identity, state)
            self.last = time.monotonic()


def _merge_chunks(todo: list[ChunkTask], state: OrderedMerge, executor: Executor | Any | None,
                  n_robots: int, resumed: int, progress: bool, checkpoint: _Checkpoint
                  ) -> None:
    """Run the chunks ``todo`` and merge their histograms into ``state`` as they arrive,
    saving the checkpoint on the way and when stopped (the chunks done so far are kept)."""
    from tqdm import tqdm

    with tqdm(total=n_robots, initial=resumed,
              disable=not progress, unit="robot", desc="Monte Carlo") as bar:
        try:
            for i, res in map_tasks(run_chunk, todo, executor):
                assert isinstance(res, ChunkResult)
                state.add(res)
                bar.update(todo[i].size)
                checkpoint.save(state)
        finally:  # also when stopped: the chunks done so far are kept
            checkpoint.save(state, now=True)


def monte_carlo_summary(model: Manipulator, q: ArrayLike, tolerances: Tolerances,
                        n_robots: int, *, seed: int | None = None,
                        rng: np.random.Generator | None = None,
                        distribution: str = "uniform", chunk: int | None = None,
                        progress: bool = False, first_order: bool = False,
                        percentiles: tuple[float, ...] = DEFAULT_PERCENTILES,
                        executor: Executor | Any | None = None,
                        checkpoint: str | os.PathLike[str] | None = None, resume: bool = False,
                        overwrite: bool = False,
                        checkpoint_every_s: float = 5.0) -> MonteCarloSummary:
    """:func:`~zrp.manufacturing.population.monte_carlo` reduced on the workers (same
    arguments): each chunk returns two histograms (four with ``first_order``), merged as they
    arrive, so the memory does not grow with ``n_robots`` (give ``seed`` for very large runs:
    with ``rng`` the draws are made here and shipped). The histograms are merged in chunk
    order (a result that arrives early waits, a few KB, for the ones before it), so even the
    floating-point sums behind the mean are the same bit for bit on any number of workers.

    Args:
        checkpoint: a ``.npz`` file the merge state is written to every ``checkpoint_every_s``
            seconds, when the run stops (an error, Ctrl-C) and at the end
            (:mod:`~zrp.manufacturing.checkpoint`; needs ``seed``).
        resume: continue the run the checkpoint holds (the same inputs, else an error naming
            those that differ); the result equals an uninterrupted run's bit for bit.
        overwrite: replace a checkpoint that exists (without ``resume``, or of another run).
    """
    for pct in percentiles:
        check_percentile(pct, "percentiles")
    if checkpoint is not None:
        check_float(checkpoint_every_s, "checkpoint_every_s", 0.0, open_lo=True, unit="s")
    edges = histogram_edges(model, q, tolerances)
    tasks = chunk_tasks(model, q, tolerances, n_robots, rng=rng, seed=seed,
                        distribution=distribution, chunk=chunk, first_order=first_order,
                        edges=edges)
    state = OrderedMerge([Histogram.of(np.empty(0), e) for e in edges * (1 + first_order)])
    identity: dict[str, str] = {}
    if checkpoint is not None:
        identity = run_identity(tasks)
        state = load_merge(checkpoint, identity, edges, resume=resume, overwrite=overwrite,
                           sizes=[t.size for t in tasks]) or state
        save_merge(checkpoint, identity, state)  # fails here, before any work, if unwritable
    todo = [t for t in tasks if not state.done(t.index)]
    resumed = n_robots - sum(t.size for t in todo)
    _merge_chunks(todo, state, executor, n_robots, resumed, progress,
                  _Checkpoint(checkpoint, identity, checkpoint_every_s))
    assert not state.waiting and state.ready == len(tasks)  # map_tasks yields every task once
    m = state.merged
    fo = (m[2], m[3]) if first_order else (None, None)
    return MonteCarloSummary(m[0], m[1], tasks[0].tolerances, distribution,
                             int(tasks[0].arrays[0].shape[0]), state.elapsed_s,
                             model.length_unit, tuple(percentiles), fo[0], fo[1], resumed)
