"""Time segments (the split), the phases of the motion (the "where") and the noise floor.

Neighbouring samples of a tracker stream share their errors (a slowly varying gap), so a
random split by sample would leak: the withheld samples would sit between fitted ones. The
motion diagnosis splits by *time segments* instead: the stream is cut into ``n_segments``
contiguous blocks; a seeded random 25 % of the blocks are withheld, the others are dealt to
the cross-validation folds, block by block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64, I64
from zrp.errors import InputError
from zrp.gap.motion.data import Trajectory

__all__ = ["PHASES", "Phases", "TimeSplit", "phases", "split_segments", "stream_noise_sigma"]

PHASES = ("reversal", "high_speed", "acceleration", "after_stop", "other")


@dataclass(frozen=True, eq=False)
class TimeSplit:
    """Samples per role (indices into the trajectory).

    Attributes:
        segment: segment of each sample, shape (S,).
        fitting, withheld: sample indices, in time order.
        folds: a partition of ``fitting`` by whole segments.
        withheld_segments: the withheld segment numbers.
    """

    segment: I64
    fitting: I64
    withheld: I64
    folds: tuple[I64, ...]
    withheld_segments: tuple[int, ...]


def split_segments(traj: Trajectory, rng: np.random.Generator, n_segments: int = 20,
                   withheld_fraction: float = 0.25, folds: int = 5) -> TimeSplit:
    """Cut the stream into ``n_segments`` blocks of equal duration; withhold a seeded random
    ``withheld_fraction`` of them; deal the rest to ``folds`` folds."""
    if not 0.0 < withheld_fraction < 1.0:
        raise InputError(f"withheld_fraction: expected a value in (0, 1), got "
                         f"{withheld_fraction}")
    if folds < 2 or n_segments < folds + 2:
        raise InputError(f"n_segments: expected at least folds + 2 = {folds + 2} segments and "
                         f"folds >= 2, got {n_segments} and {folds}")
    t = traj.t
    edges = np.linspace(t[0], t[-1], n_segments + 1)
    seg = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, n_segments - 1)
    order = rng.permutation(n_segments)
    n_with = max(1, round(withheld_fraction * n_segments))
    wseg = np.sort(order[:n_with])
    held = np.isin(seg, wseg)
    fitting = np.flatnonzero(~held)
    fold_of = {int(g): i % folds for i, g in enumerate(order[n_with:])}
    fid = np.array([fold_of[int(g)] for g in seg[fitting]])
    fl = tuple(fitting[fid == f] for f in range(folds) if np.any(fid == f))
    return TimeSplit(seg.astype(np.int64), fitting, np.flatnonzero(held), fl,
                     tuple(int(g) for g in wseg))


@dataclass(frozen=True, eq=False)
class Phases:
    """Which phase of the motion each sample is in (a sample may be in several).

    Attributes:
        masks: phase name -> bool mask, shape (S,) each (names in :data:`PHASES`).
    """

    masks: dict[str, NDArray[np.bool_]]


def phases(traj: Trajectory, window: float = 0.05, settle: float = 0.3) -> Phases:
    """Classify the samples from the commanded motion.

    * ``reversal``: within ``window`` s of a sign change of a joint's velocity while that joint
      moves at >= 5 % of its top speed within the window;
    * ``high_speed``: some joint at >= 60 % of its top speed;
    * ``acceleration``: some joint at >= 50 % of its top acceleration;
    * ``after_stop``: within ``settle`` s after all joints came to rest (< 1 % of top speed)
      from motion;
    * ``other``: none of these.
    """
    t, v, a = traj.t, traj.qd, traj.qdd
    vmax = np.abs(v).max(axis=0)
    amax = np.abs(a).max(axis=0)
    moving = vmax > 0
    rel_v = np.where(moving, np.abs(v) / np.where(moving, vmax, 1.0), 0.0)
    rel_a = np.where(amax > 0, np.abs(a) / np.where(amax > 0, amax, 1.0), 0.0)
    rev_t = []
    for k in np.flatnonzero(moving):
        sg = np.sign(v[:, k])
        idx = np.flatnonzero(sg[1:] * sg[:-1] < 0)
        for i in idx:
            lo, hi = np.searchsorted(t, [t[i] - window, t[i] + window])
            if rel_v[lo:hi, k].max(initial=0.0) >= 0.05:
                rev_t.append(t[i])
    rest = rel_v.max(axis=1) < 0.01
    stop_t = t[1:][rest[1:] & ~rest[:-1]]
    masks = {"reversal": _near(t, np.array(rev_t), window, window),
             "high_speed": rel_v.max(axis=1) >= 0.6,
             "acceleration": rel_a.max(axis=1) >= 0.5,
             "after_stop": _near(t, stop_t, 0.0, settle)}
    masks["other"] = ~np.any(np.stack(list(masks.values())), axis=0)
    return Phases(masks)


def _near(t: F64, events: F64, before: float, after: float) -> NDArray[np.bool_]:
    """Samples within [event - before, event + after] of any event."""
    out = np.zeros(t.shape, dtype=bool)
    for e in np.asarray(events):
        lo, hi = np.searchsorted(t, [e - before, e + after], side="left")
        out[lo:hi + 1] = True
    return out


def stream_noise_sigma(traj: Trajectory) -> tuple[float, int]:
    """Per-coordinate tracker noise from the second differences of each point's stream (eq.
    M4): for white noise of sigma, x_{i+1} - 2 x_i + x_{i-1} has variance 6 sigma^2, while
    the motion adds only dt^2 x'' (1 um at 1 kHz and 1 m/s^2). Robust: 1.4826 x the median
    absolute value. Returns sigma (length unit) and the number of differences used."""
    x = traj.xyz  # (S, M, 3)
    if x.shape[0] < 3:
        return float("nan"), 0
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    d2 = d2.ravel()
    return float(1.4826 * np.median(np.abs(d2)) / np.sqrt(6.0)), int(d2.size)
