"""Joint velocities and accelerations of a torque log by a zero-phase filter.

The filter is Savitzky-Golay (:func:`scipy.signal.savgol_filter`, eq. D1): at each sample a
polynomial of degree ``polyorder`` (3) is fitted by least squares to the ``window_s`` seconds
around it, and its value and derivatives at the centre are taken. Why this one:

* zero phase: the window is symmetric, so velocities and accelerations are not delayed
  against the torques (a causal filter's lag would read as a spurious inertia or damping);
* the derivatives are those of the local polynomial, not finite differences of a filtered
  signal: noise is not amplified twice;
* it keeps the peaks of a smooth trajectory better than a Butterworth ``filtfilt`` of the
  same noise rejection, and its ends (``mode="interp"``: the fit of the first/last window)
  have no start-up transient.

Its -3 dB bandwidth is about fs (polyorder + 1) / (3.2 w - 4.6) for a window of w samples
(Schafer 2011); the default 0.1 s window passes the first ~10 Hz at 1 kHz: keep the
excitation well below it. The measured torques go through the same filter (``filter_torque``),
so that both sides of tau = Y(q, qd, qdd) theta see the same frequency response (Gautier's
parallel filtering).

Logs as controllers write them: the filter runs segment by segment (the log is split at gaps
by :mod:`zrp.gap.dynamics.timebase`; nothing is differentiated across a gap), on the samples'
real time stamps (a jittering clock: :mod:`zrp.gap.dynamics.localpoly`; on a uniform grid
exactly the SciPy filter). The states of the segments are concatenated, each sample carrying
its segment and log row (:attr:`States.segment`, :attr:`States.index`); take every k-th
sample per segment with :meth:`States.every`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.localpoly import local_fit

__all__ = ["States", "derive_states"]


def _empty_ints() -> np.ndarray:
    return np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class States:
    """Joint states along a log, SI, each shape (S, n): positions, velocities,
    accelerations, torques (filtered), and the unfiltered torques; per sample its segment
    (``segment``) and its row in the log (``index``); the segments too short for the window
    (``dropped``, in words)."""

    t: F64
    q: F64
    qd: F64
    qdd: F64
    tau: F64
    tau_raw: F64
    window_s: float
    segment: np.ndarray = field(default_factory=_empty_ints)
    index: np.ndarray = field(default_factory=_empty_ints)
    dropped: tuple[str, ...] = ()

    def take(self, idx: np.ndarray) -> States:
        """The samples ``idx``."""
        seg = self.segment[idx] if self.segment.size else self.segment
        rows = self.index[idx] if self.index.size else self.index
        return States(self.t[idx], self.q[idx], self.qd[idx], self.qdd[idx], self.tau[idx],
                      self.tau_raw[idx], self.window_s, seg, rows, self.dropped)

    def every(self, stride: int) -> States:
        """Every ``stride``-th sample of each segment (from its first)."""
        if not self.segment.size:
            return self.take(np.arange(0, self.t.size, stride))
        first = np.r_[0, np.flatnonzero(np.diff(self.segment)) + 1]
        pos = np.arange(self.t.size) - np.repeat(first, np.diff(np.r_[first, self.t.size]))
        return self.take(np.flatnonzero(pos % stride == 0))


def _window(dt: float, window_s: float, n: int, polyorder: int) -> int:
    w = round(window_s / dt) | 1
    if w <= polyorder + 1:
        raise InputError(f"window_s: {window_s} s is {w} samples at the log's step {dt:.3g} s; "
                         f"needs more than {polyorder + 1}: the log is too coarse for "
                         "accelerations, or the window too short")
    if w > n:
        raise InputError(f"window_s: {window_s} s is {w} samples, more than the log's longest "
                         f"segment ({n} samples)")
    return w


def _where(log: TorqueLog, a: int, b: int) -> str:
    if log.lines.size == log.n_samples:
        return f"lines {log.lines[a]}-{log.lines[b - 1]}"
    return f"samples {a}-{b - 1}"


def derive_states(log: TorqueLog, window_s: float = 0.1, polyorder: int = 3,
                  filter_torque: bool = True) -> States:
    """q, qd, qdd (and the torques) of ``log`` by Savitzky-Golay (module docstring, eq. D1),
    segment by segment (never across a gap), on the real time axis
    (:mod:`zrp.gap.dynamics.localpoly`).

    The logged velocities are used when present (filtered like the positions); otherwise
    they are the first derivative of the positions' local polynomial. A segment shorter than
    the window is left out, and named in :attr:`States.dropped`.
    """
    dt = log.dt
    longest = max(b - a for a, b in log.segment_ranges)
    w = _window(dt, window_s, longest, polyorder)
    parts: list[tuple[F64, ...]] = []
    segs, rows, dropped = [], [], []
    for k, (a, b) in enumerate(log.segment_ranges):
        if b - a < w:
            dropped.append(f"{_where(log, a, b)} ({log.t[b - 1] - log.t[a]:.3g} s between gaps, "
                           f"shorter than the {w}-sample window)")
            continue
        t = log.t[a:b]
        # one local fit of every channel: positions (or velocities) and torques together
        src = log.q[a:b] if log.qd is None else log.qd[a:b]
        both = np.hstack([src, log.tau[a:b]] + ([log.q[a:b]] if log.qd is not None else []))
        (f0, f1, f2), _ = local_fit(t, both, w, polyorder, (0, 1, 2))
        n = log.n_joints
        if log.qd is not None:
            q, qd, qdd = f0[:, 2 * n:], f0[:, :n], f1[:, :n]
        else:
            q, qd, qdd = f0[:, :n], f1[:, :n], f2[:, :n]
        tau = f0[:, n:2 * n] if filter_torque else log.tau[a:b]
        parts.append((t, q, qd, qdd, tau, log.tau[a:b]))
        segs.append(np.full(b - a, k))
        rows.append(np.arange(a, b))
    cols = [np.concatenate([p[i] for p in parts]).copy() for i in range(6)]
    return States(*cols, float(w * dt), np.concatenate(segs), np.concatenate(rows),
                  tuple(dropped))
