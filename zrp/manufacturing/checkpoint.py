"""Checkpoint of a Monte Carlo reduced on the workers: an interrupted run resumes where it
stopped and ends with the same result, bit for bit.

:func:`~zrp.manufacturing.reduction.monte_carlo_summary` merges the chunks' histograms in chunk
order (:class:`OrderedMerge`). Its whole state is small whatever the number of robots: the
merged histograms of chunks ``0 .. ready - 1``, the few chunks that finished ahead of them, and
the summed kernel time. :func:`save_merge` writes that state to one compressed ``.npz`` file
(atomically, :mod:`zrp.output`) at most every ``every_s`` seconds and at the end, so a run of
36,000 chunks writes a few hundred KB every few seconds, not a file per chunk. The file also
holds the run's identity (:func:`run_identity`: a SHA-256 of each input - model, path,
tolerances, distribution, seed, chunking, edges, first-order flag): :func:`load_merge` resumes
only the same run and otherwise names the inputs that differ. A resumed run skips the chunks
the state already holds; the others are drawn from the same ``(seed, index)`` streams, and
the merge order is the same, so the result does not depend on where the run was stopped.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from zrp.errors import InputError, OutputExistsError
from zrp.manufacturing.chunks import ChunkResult, ChunkTask
from zrp.manufacturing.histogram import Histogram
from zrp.output import write_bytes

__all__ = ["OrderedMerge", "load_merge", "run_identity", "save_merge"]

#: Format version of the checkpoint file.
VERSION = 1


@dataclass
class OrderedMerge:
    """Histograms of chunks merged in chunk order (mutable: the running state of a run).

    Attributes:
        merged: the merged histograms of chunks ``0 .. ready - 1`` (2, or 4 with first order).
        ready: number of chunks merged.
        waiting: chunks that finished before an earlier one, by index: their histograms and
            kernel time (s).
        elapsed_s: kernel time summed over the merged chunks (s).
    """

    merged: list[Histogram]
    ready: int = 0
    waiting: dict[int, tuple[tuple[Histogram, ...], float]] = field(default_factory=dict)
    elapsed_s: float = 0.0

    def done(self, index: int) -> bool:
        """Is chunk ``index`` already in the state (merged or waiting)?"""
        return index < self.ready or index in self.waiting

    def add(self, res: ChunkResult) -> None:
        """Take one chunk's histograms; merge every chunk that is now next in order."""
        if res.histograms is None or len(res.histograms) != len(self.merged):
            raise InputError(f"results: chunk {res.index} was not reduced to "
                             f"{len(self.merged)} histograms on its worker")
        self.waiting[res.index] = (res.histograms, res.elapsed_s)
        while self.ready in self.waiting:
            hists, elapsed = self.waiting.pop(self.ready)
            self.merged = [m.merge(h) for m, h in zip(self.merged, hists, strict=True)]
            self.elapsed_s += elapsed
            self.ready += 1


def _digest(*parts: Any) -> str:
    h = hashlib.sha256()
    for part in parts:
        if isinstance(part, np.ndarray):
            h.update(str((part.dtype.str, part.shape)).encode())
            h.update(np.ascontiguousarray(part).tobytes())
        else:
            h.update(pickle.dumps(part, protocol=4))
    return h.hexdigest()[:16]


def run_identity(tasks: list[ChunkTask]) -> dict[str, str]:
    """What makes two runs the same run, one short SHA-256 per input (a task list from
    :func:`~zrp.manufacturing.population.chunk_tasks` with ``seed`` and ``edges``)."""
    t = tasks[0]
    if t.seed is None or t.edges is None:
        raise InputError("checkpoint: a resumable Monte Carlo needs seed= (each chunk draws "
                         "its own robots), not rng=, and the worker-side reduction")
    m = t.model
    return {
        "model": _digest(m.axes, m.bodies, np.asarray(m.prismatic), m.length_unit),
        "path": _digest(*t.arrays),
        "tolerances": _digest(t.tolerances.values, t.tolerances.names,
                              t.tolerances.joint_offsets),
        "distribution": t.distribution,
        "seed": str(t.seed),
        "robots": str(sum(task.size for task in tasks)),
        "chunk": str(t.size),
        "first_order": str(t.first_order),
        "edges": _digest(*t.edges),
    }


def save_merge(path: str | os.PathLike[str], identity: dict[str, str],
               state: OrderedMerge) -> Path:
    """Write ``state`` and ``identity`` to ``path`` (compressed ``.npz``, replaced atomically)."""
    idx = sorted(state.waiting)
    hists = [*state.merged, *(h for i in idx for h in state.waiting[i][0])]
    buf = io.BytesIO()
    np.savez_compressed(
        buf, header=np.array(json.dumps({"version": VERSION, "identity": identity,
                                         "ready": state.ready, "waiting": idx,
                                         "per_chunk": len(state.merged)})),
        counts=np.stack([h.counts for h in hists]),
        stats=np.array([[h.total, h.minimum, h.maximum, h.sum, h.sumsq] for h in hists]),
        elapsed=np.array([state.elapsed_s, *(state.waiting[i][1] for i in idx)]))
    return write_bytes(path, buf.getvalue(), overwrite=True)


def _read(p: Path) -> tuple[dict[str, Any], Any]:
    try:
        z = np.load(p, allow_pickle=False)
        head = json.loads(str(z["header"]))
        if head.get("version") != VERSION:
            raise InputError(f"checkpoint {p}: format version {head.get('version')!r}, "
                             f"expected {VERSION}")
        return head, z
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(f"checkpoint {p}: not a Monte Carlo checkpoint of this version "
                         f"({exc}); remove it or give another file") from exc


def load_merge(path: str | os.PathLike[str], identity: dict[str, str],
               edges: tuple[Any, ...], *, resume: bool,
               overwrite: bool) -> OrderedMerge | None:
    """The state saved at ``path`` when it holds this run and ``resume`` is True; None to
    start afresh (no file, or ``overwrite``).

    Raises:
        OutputExistsError: the file exists and neither ``resume`` nor ``overwrite`` is set.
        InputError: ``resume`` but the file holds another run (the differing inputs named).
    """
    p = Path(path)
    if not p.exists() or (overwrite and not resume):
        return None
    head, z = _read(p)
    if not resume:
        raise OutputExistsError([p], option="resume=True to continue it, or overwrite=True")
    theirs = head["identity"]
    differ = [k for k in identity if theirs.get(k) != identity[k]]
    if differ:
        if overwrite:
            return None
        raise InputError(f"checkpoint {p}: holds another run (different "
                         f"{', '.join(differ)}); give the same inputs to resume it, or "
                         f"another file")
    counts, stats, elapsed = z["counts"], z["stats"], z["elapsed"]
    hists = [Histogram(edges[k % 2], counts[k], int(stats[k, 0]), *map(float, stats[k, 1:]))
             for k in range(counts.shape[0])]  # (delta_p, angle) edges, repeated
    n = int(head["per_chunk"])
    state = OrderedMerge(hists[:n], int(head["ready"]), elapsed_s=float(elapsed[0]))
    for j, i in enumerate(head["waiting"]):
        state.waiting[int(i)] = (tuple(hists[n * (j + 1):n * (j + 2)]), float(elapsed[j + 1]))
    return state
