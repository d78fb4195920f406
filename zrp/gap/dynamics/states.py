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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog

__all__ = ["States", "derive_states"]


@dataclass(frozen=True)
class States:
    """Joint states along a log, SI, each shape (S, n): positions, velocities,
    accelerations, torques (filtered), and the unfiltered torques."""

    t: F64
    q: F64
    qd: F64
    qdd: F64
    tau: F64
    tau_raw: F64
    window_s: float

    def take(self, idx: np.ndarray) -> States:
        """The samples ``idx``."""
        return States(self.t[idx], self.q[idx], self.qd[idx], self.qdd[idx], self.tau[idx],
                      self.tau_raw[idx], self.window_s)


def _window(dt: float, window_s: float, n: int, polyorder: int) -> int:
    w = round(window_s / dt) | 1
    if w <= polyorder + 1:
        raise InputError(f"window_s: {window_s} s is {w} samples at the log's step {dt:.3g} s; "
                         f"needs more than {polyorder + 1}: the log is too coarse for "
                         "accelerations, or the window too short")
    if w > n:
        raise InputError(f"window_s: {window_s} s is {w} samples, more than the log's {n}")
    return w


def derive_states(log: TorqueLog, window_s: float = 0.1, polyorder: int = 3,
                  filter_torque: bool = True) -> States:
    """q, qd, qdd (and the torques) of ``log`` by Savitzky-Golay (module docstring, eq. D1).

    The logged velocities are used when present (filtered like the positions); otherwise
    they are the first derivative of the positions' local polynomial.
    """
    dt = log.dt
    w = _window(dt, window_s, log.n_samples, polyorder)

    def sg(x: F64, deriv: int = 0) -> F64:
        return savgol_filter(x, w, polyorder, deriv=deriv, delta=dt, axis=0, mode="interp")

    q = sg(log.q)
    if log.qd is not None:
        qd = sg(log.qd)
        qdd = sg(log.qd, 1)
    else:
        qd = sg(log.q, 1)
        qdd = sg(log.q, 2)
    tau = sg(log.tau) if filter_torque else log.tau.copy()
    return States(log.t.copy(), q, qd, qdd, tau, log.tau.copy(), float(w * dt))
