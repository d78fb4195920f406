"""Joint-space test trajectories: rest-to-rest quintic moves between waypoints with dwells.

They exercise what motion effects need: high speed mid-move, acceleration at both ends,
stops (the dwells) and velocity reversals (a joint moving back after a dwell). The path is
analytic, so it can be evaluated at any time (a delayed or filtered copy for tests).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["JointMoves", "exercise_moves"]



@dataclass(frozen=True, eq=False)
class JointMoves:
    """Waypoints (K + 1, n) visited in order; move k takes ``durations[k]`` s (quintic time law
    s(x) = 10 x^3 - 15 x^4 + 6 x^5, at rest at both ends) and is followed by ``dwell`` s."""

    waypoints: F64
    durations: F64
    dwell: float = 0.2

    def __post_init__(self) -> None:
        w = np.asarray(self.waypoints, dtype=float)
        d = np.asarray(self.durations, dtype=float)
        if w.ndim != 2 or d.shape != (w.shape[0] - 1,) or np.any(d <= 0) or self.dwell < 0:
            raise InputError(f"JointMoves: expected waypoints (K + 1, n) and K durations > 0 s, "
                             f"got {w.shape} and {d.shape}")
        object.__setattr__(self, "waypoints", w)
        object.__setattr__(self, "durations", d)
        starts = np.concatenate([[0.0], np.cumsum(d + self.dwell)[:-1]]) + self.dwell
        object.__setattr__(self, "_starts", starts)

    @property
    def duration(self) -> float:
        """Total time, s (dwells before the first and after the last move included)."""
        return float(self._starts[-1] + self.durations[-1] + self.dwell)  # type: ignore[attr-defined]

    def __call__(self, t: ArrayLike, order: int = 0) -> F64:
        """Joint values (order 0), velocities (1) or accelerations (2) at times t (s), shape
        (..., n)."""
        t = np.asarray(t, dtype=float)
        w = self.waypoints
        starts = self._starts  # type: ignore[attr-defined]
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        T = self.durations[k]
        x = np.clip((t - starts[k]) / T, 0.0, 1.0)
        inside = (t >= starts[k]) & (t <= starts[k] + T)
        delta = w[k + 1] - w[k]
        if order == 0:
            s = x**3 * (10 - 15 * x + 6 * x * x)
            before = t < starts[0]
            out = w[k] + s[..., None] * delta
            return np.where(before[..., None], w[0], out)
        if order == 1:
            ds = 30 * x * x * (1 - x) ** 2 / T
        elif order == 2:
            ds = (60 * x - 180 * x * x + 120 * x**3) / T**2
        else:
            raise InputError(f"order: expected 0, 1 or 2, got {order}")
        return np.where(inside[..., None], ds[..., None] * delta, 0.0)


def exercise_moves(q0: ArrayLike, rng: np.random.Generator, moves: int = 12,
                   amplitude: float = 0.6, duration: tuple[float, float] = (0.6, 1.2),
                   dwell: float = 0.25, limits: ArrayLike | None = None) -> JointMoves:
    """Random moves about q0 (rad): each joint goes to q0 + U(-amplitude, amplitude) (clipped
    to ``limits`` (n, 2) when given), alternating sides so that joints reverse often."""
    q0 = np.asarray(q0, dtype=float)
    n = q0.size
    pts = [q0]
    side = np.ones(n)
    for _ in range(moves):
        side = -side
        step = side * rng.uniform(0.3, 1.0, n) * amplitude
        nxt = q0 + step
        if limits is not None:
            lim = np.asarray(limits, dtype=float)
            nxt = np.clip(nxt, lim[:, 0], lim[:, 1])
        pts.append(nxt)
    durs = rng.uniform(duration[0], duration[1], moves)
    return JointMoves(np.array(pts), durs, dwell)
