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
import math
import os
import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from zrp.errors import InputError, OutputExistsError
from zrp.jsonio import version_field
from zrp.manufacturing.chunks import ChunkResult, ChunkTask
from zrp.manufacturing.histogram import Histogram
from zrp.output import write_bytes
from zrp.textio import check_file

__all__ = ["OrderedMerge", "load_merge", "run_identity", "save_merge"]

#: Format version of the checkpoint file (2: with the SHA-256 of its content).
VERSION = 2
#: Largest checkpoint file read (its state is a few hundred KB whatever the run).
MAX_CHECKPOINT_BYTES = 256 * 2**20


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


def _content_hash(head: str, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of the header text and of every array (name, dtype, shape, bytes)."""
    h = hashlib.sha256(head.encode("utf-8"))
    for name in sorted(arrays):
        a = arrays[name]
        h.update(f"\0{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def save_merge(path: str | os.PathLike[str], identity: dict[str, str],
               state: OrderedMerge) -> Path:
    """Write ``state`` and ``identity`` to ``path`` (compressed ``.npz``, replaced atomically),
    with the SHA-256 of its content (checked by :func:`load_merge`)."""
    idx = sorted(state.waiting)
    hists = [*state.merged, *(h for i in idx for h in state.waiting[i][0])]
    head = json.dumps({"version": VERSION, "identity": identity, "ready": state.ready,
                       "waiting": idx, "per_chunk": len(state.merged)}, sort_keys=True)
    arrays = {
        "counts": np.stack([h.counts for h in hists]).astype(np.int64),
        "stats": np.array([[h.total, h.minimum, h.maximum, h.sum, h.sumsq] for h in hists],
                          dtype=float),
        "elapsed": np.array([state.elapsed_s, *(state.waiting[i][1] for i in idx)],
                            dtype=float)}
    buf = io.BytesIO()
    np.savez_compressed(buf, header=np.array(head), sha256=np.array(_content_hash(head, arrays)),
                        **arrays)
    return write_bytes(path, buf.getvalue(), overwrite=True)


def _read(p: Path) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header and the arrays of a checkpoint, its SHA-256 checked: any damage (empty,
    truncated, bit-flipped, edited, not an .npz) is an :class:`InputError` naming the file."""
    check_file(p, f"checkpoint {p}", MAX_CHECKPOINT_BYTES, False, InputError)
    fix = "remove it to start afresh (or give another file)"
    try:
        with np.load(p, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        head_text = str(data.pop("header"))
        digest = str(data.pop("sha256"))
    except Exception as exc:  # zipfile, zlib, numpy, EOF: every way a damaged file fails
        raise InputError(f"checkpoint {p}: not a Monte Carlo checkpoint, or a damaged one "
                         f"({type(exc).__name__}: {exc}); {fix}") from None
    if digest != _content_hash(head_text, data):
        raise InputError(f"checkpoint {p}: its content does not match the SHA-256 it was "
                         f"written with (the file was changed or damaged); {fix}")
    try:
        head = json.loads(head_text)
    except ValueError as exc:
        raise InputError(f"checkpoint {p}: its header is not JSON ({exc}); {fix}") from None
    if not isinstance(head, dict):
        raise InputError(f"checkpoint {p}: its header is not a JSON object; {fix}")
    version_field(head, "version", (VERSION,), src=f"checkpoint {p}", hint=f"; {fix}")
    return head, data


def _bad(p: Path, field: str, why: str) -> InputError:
    return InputError(f"checkpoint {p}: field {field} {why}; remove the file to start afresh")


def _is_int(v: Any) -> bool:
    return type(v) is int


def _header_fields(p: Path, head: dict[str, Any], n_chunks: int | None
                   ) -> tuple[int, list[int], int]:
    """(ready, waiting, per_chunk) of the header, each of the right type and range."""
    ready, waiting, per = head.get("ready"), head.get("waiting"), head.get("per_chunk")
    if not isinstance(head.get("identity"), dict):
        raise _bad(p, "identity", "is not a table of the run's inputs")
    if not _is_int(per) or per not in (2, 4):
        raise _bad(p, "per_chunk", f"is {per!r}; expected 2 or 4 histograms a chunk")
    top = n_chunks if n_chunks is not None else math.inf
    if not _is_int(ready) or not 0 <= ready <= top:
        raise _bad(p, "ready", f"is {ready!r}; expected a chunk count 0..{n_chunks}")
    ok = isinstance(waiting, list) and all(_is_int(i) and ready < i < top for i in waiting)
    if not ok or len(set(waiting)) != len(waiting):
        raise _bad(p, "waiting", f"is {str(waiting)[:80]}; expected distinct chunk indices "
                   f"after ready={ready}")
    return ready, list(waiting), per


def _array_fields(p: Path, data: dict[str, np.ndarray], k: int, n_wait: int) -> None:
    """counts (k, B), stats (k, 5) and elapsed (1 + n_wait,) of the right kinds."""
    shapes = {"counts": (k, None), "stats": (k, 5), "elapsed": (1 + n_wait,)}
    for name, shape in shapes.items():
        a = data.get(name)
        if a is None or a.shape[:1] != shape[:1] or a.ndim != len(shape) \
                or (len(shape) == 2 and shape[1] is not None and a.shape[1] != shape[1]):
            raise _bad(p, name, f"has shape {None if a is None else a.shape}; expected "
                       f"{tuple('B' if s is None else s for s in shape)}")
    el = data["elapsed"]
    if data["counts"].dtype.kind not in "iu" or el.dtype.kind != "f" \
            or not np.all(np.isfinite(el)) or np.any(el < 0):
        raise _bad(p, "counts/elapsed", "holds values of the wrong kind (negative or not "
                   "finite)")


def _fields(p: Path, head: dict[str, Any], data: dict[str, np.ndarray],
            sizes: list[int] | None) -> tuple[int, list[int], int]:
    """(ready, waiting, per_chunk) after every field was checked against the arrays and the
    run's chunk sizes (``sizes``); a field out of place is an error naming it."""
    ready, waiting, per = _header_fields(p, head, None if sizes is None else len(sizes))
    _array_fields(p, data, per * (1 + len(waiting)), len(waiting))
    if sizes is not None:
        want = [sum(sizes[:ready])] * per + [sizes[i] for i in waiting for _ in range(per)]
        got = [int(v) if np.isfinite(v) else -1 for v in data["stats"][:, 0]]
        if got != want:
            raise _bad(p, "ready", f"= {ready} with waiting {waiting} does not match the "
                       f"robots its histograms count ({got[0]} robots merged, expected "
                       f"{want[0]})")
    return ready, waiting, per


def load_merge(path: str | os.PathLike[str], identity: dict[str, str],
               edges: tuple[Any, ...], *, resume: bool,
               overwrite: bool, sizes: list[int] | None = None) -> OrderedMerge | None:
    """The state saved at ``path`` when it holds this run and ``resume`` is True; None to
    start afresh (no file, or ``overwrite``). ``sizes``: the run's chunk sizes, against which
    the state's robot counts are checked.

    Raises:
        OutputExistsError: the file exists and neither ``resume`` nor ``overwrite`` is set.
        InputError: the file is damaged or edited (its SHA-256 or a field does not match,
            named), or ``resume`` but the file holds another run (the differing inputs named).
    """
    p = Path(path)
    if not p.exists() or (overwrite and not resume):
        return None
    head, z = _read(p)
    if not resume:
        raise OutputExistsError([p], option="resume=True to continue it, or overwrite=True")
    theirs = head.get("identity")
    differ = [k for k in identity if not isinstance(theirs, dict)
              or theirs.get(k) != identity[k]]
    if differ:
        if overwrite:
            return None
        raise InputError(f"checkpoint {p}: holds another run (different "
                         f"{', '.join(differ)}); give the same inputs to resume it, or "
                         f"another file")
    ready, waiting, n = _fields(p, head, z, sizes)
    counts, stats, elapsed = z["counts"], z["stats"], z["elapsed"]
    try:
        hists = [Histogram(edges[k % 2], counts[k], int(stats[k, 0]), *map(float, stats[k, 1:]))
                 for k in range(counts.shape[0])]  # (delta_p, angle) edges, repeated
    except (InputError, ValueError, OverflowError) as exc:
        raise InputError(f"checkpoint {p}: a histogram does not fit this run's bins ({exc}); "
                         "remove the file to start afresh") from None
    state = OrderedMerge(hists[:n], ready, elapsed_s=float(elapsed[0]))
    for j, i in enumerate(waiting):
        state.waiting[i] = (tuple(hists[n * (j + 1):n * (j + 2)]), float(elapsed[j + 1]))
    return state
