"""A controller's log of a simulated arm, with the defects that real controller logs have.

:func:`controller_log` takes a clean simulated log (a constant 1 kHz step, no noise: the
physics, :func:`sim.studies.dynamics.truth.simulate` with ``noise_nm=0``) and makes the log a
controller would write (:class:`LogDefects`, each one optional):

* clock jitter: steps of ``step_s`` (0.8 to 1.6 ms) around the nominal 1 ms: most within
  +-0.1 ms (a normal draw, clipped), a few late ones (``late_share``) up to 1.6 ms;
* gaps: ``gaps`` (8) steps of 2 to 9 ms (samples the logger lost);
* the states and torques at these times: cubic interpolation of the clean 1 kHz physics;
* motion-locked vibration: a torque ripple locked to joint position (a gear or cogging
  harmonic) A_k sin(2 pi h q_k / (2 pi) + phi_k) = A_k sin(h q_k + phi_k), ``ripple_order``
  h periods per radian, A_k = ``ripple_sigma`` times joint k's noise;
* torque noise N(0, sigma_k^2) and encoder noise, then quantisation: torques to
  ``torque_lsb_nm``, positions to ``encoder_lsb_rad``;
* repeated rows: ``repeat_share`` (5 %) of the written rows are exact copies of the row
  before (time stamp included: a logger that read the same state twice).

:func:`write_controller_log` writes it as a CSV with the standard torque log's columns
(``t [s], q1 [rad] .., qd1 [rad/s] .., tau1 [Nm] ..``, read by
:func:`zrp.gap.dynamics.data.load_torque_log`) or with a controller's own names
(:data:`NAMINGS`: libfranka-like ``time, q_0.., dq_0.., tau_J_0..``; UR RTDE-like
``timestamp, actual_q_0.., actual_qd_0.., actual_current_0..`` with the currents = torque / k_t
and k_t stated in a ``# torque_constant`` comment line).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog
from zrp.output import write_text

__all__ = ["NAMINGS", "ControllerLog", "LogDefects", "controller_log", "log_times",
           "write_controller_log"]

NAMINGS = ("standard", "franka", "rtde")


@dataclass(frozen=True)
class LogDefects:
    """Which real-log defects to apply and how large (module docstring); the default is a
    clean log (a constant step, noise only)."""

    jitter: bool = False
    step_s: tuple[float, float] = (0.8e-3, 1.6e-3)
    jitter_sd_s: float = 0.1e-3
    late_share: float = 0.03
    gaps: int = 0
    gap_s: tuple[float, float] = (2e-3, 9e-3)
    repeat_share: float = 0.0
    torque_lsb_nm: float = 0.0
    encoder_lsb_rad: float = 0.0
    ripple_sigma: float = 0.0
    ripple_order: float = 16.0
    naming: str = "standard"

    def __post_init__(self) -> None:
        if self.naming not in NAMINGS:
            raise InputError(f"naming: {self.naming!r}; expected one of {', '.join(NAMINGS)}")

    @classmethod
    def real(cls, naming: str = "standard", torque_lsb_nm: float = 0.02) -> LogDefects:
        """Every defect of issue 32 at its stated size."""
        return cls(jitter=True, gaps=8, repeat_share=0.05, torque_lsb_nm=torque_lsb_nm,
                   encoder_lsb_rad=2.0 * np.pi / 2**18, ripple_sigma=1.0, naming=naming)

    @property
    def clean(self) -> bool:
        return self == LogDefects(naming=self.naming)


@dataclass(frozen=True)
class ControllerLog:
    """What the controller wrote: rows (repeats included), SI units."""

    t: F64
    q: F64
    qd: F64
    tau: F64
    defects: LogDefects
    repeated_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ripple_nm: F64 = field(default_factory=lambda: np.zeros(0))


def log_times(t0: float, t1: float, defects: LogDefects, rng: np.random.Generator,
              nominal_s: float = 1e-3) -> F64:
    """The controller's time stamps in [t0, t1]: jittered steps and gaps (module docstring),
    or the nominal step."""
    n = int(np.floor((t1 - t0) / nominal_s)) + 1
    if not defects.jitter and defects.gaps == 0:
        return t0 + nominal_s * np.arange(n)
    lo, hi = defects.step_s
    steps = np.full(n, nominal_s)
    if defects.jitter:
        steps = np.clip(nominal_s + rng.normal(size=n) * defects.jitter_sd_s, lo, hi)
        late = rng.random(n) < defects.late_share
        steps[late] = rng.uniform(nominal_s + 0.2e-3, hi, int(late.sum()))
    if defects.gaps:
        # away from the ends (the first and last 5 %), each gap its own step
        at = rng.choice(np.arange(n // 20, n - n // 20), defects.gaps, replace=False)
        steps[at] = rng.uniform(*defects.gap_s, defects.gaps)
    t = t0 + np.concatenate([[0.0], np.cumsum(steps)])
    return t[t <= t1]


def _repeat(n: int, share: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Row order with ``share`` of the output rows copies of the one before, and their
    output positions."""
    k = round(share * n / (1.0 - share)) if share > 0.0 else 0
    src = np.sort(rng.choice(np.arange(1, n), k, replace=False)) if k else np.zeros(0, int)
    order = np.insert(np.arange(n), np.searchsorted(np.arange(n), src, side="right"), src)
    pos = np.flatnonzero(np.diff(order) == 0) + 1
    return order, pos


def controller_log(clean: TorqueLog, noise_nm: F64, defects: LogDefects, *, seed: int = 0,
                   encoder_noise_rad: float = 1e-5) -> ControllerLog:
    """The log a controller writes of the clean physics ``clean`` (module docstring)."""
    if clean.qd is None:
        raise InputError("clean: the simulated log needs its velocities")
    rng = np.random.default_rng([seed, 7])
    t = log_times(float(clean.t[0]), float(clean.t[-1]), defects, rng, clean.dt)
    q, qd, tau = (CubicSpline(clean.t, x, axis=0)(t) for x in (clean.q, clean.qd, clean.tau))
    n = q.shape[1]
    sigma = np.broadcast_to(np.asarray(noise_nm, dtype=float), (n,))
    amp = defects.ripple_sigma * sigma
    tau = tau + amp * np.sin(defects.ripple_order * q + rng.uniform(0, 2 * np.pi, n))
    tau = tau + rng.normal(size=tau.shape) * sigma
    q = q + rng.normal(size=q.shape) * encoder_noise_rad
    if defects.torque_lsb_nm > 0.0:
        tau = np.round(tau / defects.torque_lsb_nm) * defects.torque_lsb_nm
    if defects.encoder_lsb_rad > 0.0:
        q = np.round(q / defects.encoder_lsb_rad) * defects.encoder_lsb_rad
    order, pos = _repeat(t.size, defects.repeat_share, rng)
    return ControllerLog(t[order], q[order], qd[order], tau[order], defects, pos, amp)


def _header(naming: str, n: int) -> list[str]:
    if naming == "franka":
        return (["time"] + [f"q_{k}" for k in range(n)] + [f"dq_{k}" for k in range(n)]
                + [f"tau_J_{k}" for k in range(n)])
    if naming == "rtde":
        return (["timestamp"] + [f"actual_q_{k}" for k in range(n)]
                + [f"actual_qd_{k}" for k in range(n)]
                + [f"actual_current_{k}" for k in range(n)])
    return (["t [s]"] + [f"q{k + 1} [rad]" for k in range(n)]
            + [f"qd{k + 1} [rad/s]" for k in range(n)] + [f"tau{k + 1} [Nm]" for k in range(n)])


def write_controller_log(log: ControllerLog, path: str | os.PathLike[str], *,
                         torque_constant: F64 | None = None, overwrite: bool = False) -> Path:
    """Write ``log`` as a CSV in its naming (module docstring); ``torque_constant`` (N m/A per
    joint) is needed for the RTDE-like currents."""
    n = log.q.shape[1]
    naming = log.defects.naming
    effort = log.tau
    lines = [",".join(_header(naming, n))]
    if naming == "rtde":
        if torque_constant is None or np.shape(torque_constant) != (n,):
            raise InputError(f"torque_constant: the RTDE-like log needs {n} values (N m/A)")
        effort = log.tau / np.asarray(torque_constant)
        lines.append("# torque_constant [Nm/A]: "
                     + " ".join(f"{k:.6g}" for k in torque_constant))
    data = np.column_stack([log.t, log.q, log.qd, effort])
    lines += [",".join(f"{v:.10g}" for v in row) for row in data]
    return write_text(Path(path), "\n".join(lines) + "\n", overwrite=overwrite)
