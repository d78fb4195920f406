"""Re-simulation of a commanded trajectory through a MuJoCo model with a joint servo
(``mj_step``): the controller every model shares (the nominal model's inverse dynamics as
feed-forward plus PD feedback), and the tracking gap of a model along a logged command.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Protocol

import mujoco
import numpy as np
from scipy.interpolate import CubicSpline

from mjcf.arm import Arm
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.inertia import V_EPS

__all__ = ["TRUTH_V_EPS", "Command", "Run", "SampledCommand", "Servo", "TrackingGap",
           "run_servo", "track_log", "tracking_gap"]

#: Velocity scale of an applied Stribeck bump's sign, rad/s (not the diagnosis's V_EPS).
TRUTH_V_EPS = 0.02


class Command(Protocol):
    """A commanded trajectory: positions, velocities, accelerations at times ``t``."""

    def evaluate(self, t: F64) -> tuple[F64, F64, F64]: ...


@dataclass(frozen=True)
class Servo:
    """tau = ID_nominal(qc, qcd, qcdd) + kp (qc - q) + kv (qcd - qd); kp, kv (n,)."""

    kp: F64
    kv: F64

    @classmethod
    def tuned(cls, arm: Arm, q0: F64, hz: float = 4.0, zeta: float = 1.0) -> Servo:
        """Gains for a ``hz`` bandwidth from the nominal joint inertias at q0."""
        m = arm.model
        d = mujoco.MjData(m)
        d.qpos[:] = q0
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        w = 2.0 * np.pi * hz
        inertia = np.diag(full)
        return cls(inertia * w * w, 2.0 * zeta * inertia * w)


def _plant(m: mujoco.MjModel, dt: float) -> mujoco.MjModel:
    m = copy.deepcopy(m)
    m.opt.timestep = dt
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT
                              | mujoco.mjtDisableBit.mjDSBL_LIMIT
                              | mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    return m


@dataclass(frozen=True)
class Run:
    """A simulated run: time, positions, velocities and the servo's torques (S, n)."""

    t: F64
    q: F64
    qd: F64
    tau: F64
    qc: F64


def run_servo(plant: mujoco.MjModel, nominal: mujoco.MjModel, servo: Servo, command: Command,
              duration_s: float, rate_hz: float = 1000.0, substeps: int = 4,
              stribeck: tuple[F64, float] | None = None, moving_start: bool = False) -> Run:
    """Drive ``plant`` along ``command`` with ``servo`` (feed-forward from ``nominal``),
    starting at the command's first position, at rest (or at its velocity: ``moving_start``,
    for a stretch of a log that starts in motion)."""
    dt = 1.0 / (rate_hz * substeps)
    p = _plant(plant, dt)
    d = mujoco.MjData(p)
    dn = mujoco.MjData(nominal)
    steps = round(duration_s * rate_hz)
    t = np.arange(steps) / rate_hz
    tf = np.arange(steps * substeps) * dt
    qc, qcd, qcdd = command.evaluate(tf)
    d.qpos[:] = qc[0]
    if moving_start:
        d.qvel[:] = qcd[0]
    fl = np.asarray(nominal.dof_frictionloss)
    n = p.nv
    out_q, out_qd, out_tau = (np.empty((steps, n)) for _ in range(3))
    saved = nominal.opt.disableflags
    nominal.opt.disableflags = saved | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    try:
        for i in range(steps * substeps):
            dn.qpos[:], dn.qvel[:], dn.qacc[:] = qc[i], qcd[i], qcdd[i]
            mujoco.mj_inverse(nominal, dn)
            tau = (dn.qfrc_inverse + fl * np.tanh(qcd[i] / V_EPS)
                   + servo.kp * (qc[i] - d.qpos) + servo.kv * (qcd[i] - d.qvel))
            if i % substeps == 0:
                j = i // substeps
                out_q[j], out_qd[j], out_tau[j] = d.qpos, d.qvel, tau
            d.qfrc_applied[:] = tau
            if stribeck is not None:
                fs, vs = stribeck
                w = d.qvel
                d.qfrc_applied[:] -= fs * np.tanh(w / TRUTH_V_EPS) * np.exp(-(w / vs) ** 2)
            mujoco.mj_step(p, d)
    finally:
        nominal.opt.disableflags = saved
    return Run(t, out_q, out_qd, out_tau, qc[::substeps])


@dataclass(frozen=True)
class SampledCommand:
    """A logged command (t, qc) as a cubic spline, with its derivatives."""

    t: F64
    qc: F64

    @property
    def q0(self) -> F64:
        return self.qc[0]

    def evaluate(self, t: F64) -> tuple[F64, F64, F64]:
        sp = CubicSpline(self.t - self.t[0], self.qc, axis=0)
        return sp(t), sp(t, 1), sp(t, 2)


def _simulated_at(model: mujoco.MjModel, nominal: mujoco.MjModel, servo: Servo,
                  command: Command, t: F64, rate_hz: float) -> F64:
    """Positions (len(t), n) of ``model`` driven along ``command`` (which starts at t[0]),
    read at the real sample times ``t`` (a jittered clock is not a uniform grid)."""
    span = float(t[-1] - t[0])
    run = run_servo(copy.deepcopy(model), nominal, servo, command, span + 1.0 / rate_hz,
                    rate_hz, moving_start=True)
    return np.column_stack([np.interp(t - t[0], run.t, run.q[:, j])
                            for j in range(run.q.shape[1])])


def tracking_gap(model: mujoco.MjModel, nominal: mujoco.MjModel, log: TorqueLog, servo: Servo,
                 command: Command | None = None) -> F64:
    """RMS of (re-simulated minus logged) joint positions per joint (n,), ``model`` driven by
    ``servo`` (feed-forward from ``nominal``, as the real controller) along the log's
    commanded positions (or ``command``, an object with ``evaluate(t)``).

    The simulation is read at the log's own sample times, and a log split at gaps is
    re-simulated one segment at a time, each from its own start (a gap is time the log does
    not show, not time the servo ran through)."""
    rate = 1.0 / log.dt
    if command is not None:
        return np.sqrt(np.mean((_simulated_at(model, nominal, servo, command, log.t, rate)
                                - log.q) ** 2, axis=0))
    if log.qc is None:
        raise InputError(f"{log.source}: no commanded positions qc1..qcn; the "
                         "re-simulation drives them")
    sq, count = np.zeros(log.n_joints), 0
    for a, b in log.segment_ranges:
        if b - a < 4:
            continue
        seg = SampledCommand(log.t[a:b], log.qc[a:b])
        q = _simulated_at(model, nominal, servo, seg, log.t[a:b], rate)
        sq += np.sum((q - log.q[a:b]) ** 2, axis=0)
        count += b - a
    if count == 0:
        raise InputError(f"{log.source}: no stretch of at least 4 samples without a gap to "
                         "re-simulate")
    return np.sqrt(sq / count)


@dataclass(frozen=True)
class TrackingGap:
    """The logged command re-simulated through the model and the corrected model with one
    servo: RMS of simulated minus logged joint positions per joint (rad), and how the servo
    was chosen."""

    before_rad: F64
    after_rad: F64
    servo: str


def _servo(arm: Arm, q0: F64, kp: F64 | None, kv: F64 | None) -> tuple[Servo, str]:
    if (kp is None) != (kv is None):
        raise InputError("kp, kv: give both (the servo's stiffness and damping) or neither")
    if kp is None or kv is None:
        return Servo.tuned(arm, q0), "a 4 Hz servo tuned from the model (kp/kv: yours)"
    for name, v in (("kp", kp), ("kv", kv)):
        if np.asarray(v).shape != (arm.n,):
            raise InputError(f"{name}: expected {arm.n} values (one a joint), got "
                             f"{np.asarray(v).size}")
    return Servo(np.asarray(kp, dtype=float), np.asarray(kv, dtype=float)), "the servo gains given"


def _first_seconds(log: TorqueLog, seconds: float | None) -> TorqueLog:
    if seconds is None:
        return log
    return log.first(max(2, int(np.searchsorted(log.t - log.t[0], seconds))))


def track_log(arm: Arm, corrected_xml: str, log: TorqueLog, *, kp: F64 | None = None,
              kv: F64 | None = None, seconds: float | None = None) -> TrackingGap | None:
    """The tracking gap of the model and of ``corrected_xml`` along the log's commanded
    positions (None: the log has none), the first ``seconds`` only when given."""
    if log.qc is None:
        return None
    servo, how = _servo(arm, log.qc[0], kp, kv)
    part = _first_seconds(log, seconds)
    corrected = mujoco.MjModel.from_xml_string(corrected_xml)
    return TrackingGap(tracking_gap(arm.model, arm.model, part, servo),
                       tracking_gap(corrected, arm.model, part, servo), how)
