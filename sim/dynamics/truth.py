"""The physics robot with hidden dynamic effects: an arm's MuJoCo model changed by effects the
nominal model does not have, driven along a command by a joint servo (``mj_step``), logging
what a real arm logs (positions, velocities, motor torques with sensor errors and noise).

Hidden effects (:class:`HiddenDynamics`): Coulomb friction (MuJoCo ``frictionloss``, its
soft-constraint law, not the diagnosis's tanh), viscous friction (``damping``), a Stribeck
bump (an applied torque F_s tanh(w / 0.02) exp(-(w / v_s)^2)), extra armature, a payload (a
point mass at the tool point plus an offset), link inertial errors, and a torque sensor's
offset and gain. The controller (:class:`Servo`) is the same for the real arm and any model
re-simulated through the command: the nominal model's inverse dynamics along the command
(feed-forward) plus PD feedback.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import mujoco
import numpy as np

from sim.dynamics.arm import Arm
from sim.dynamics.fourier import Fourier
from sim.dynamics.inertial import V_EPS, body_params, set_body_params
from zrp.arrays import F64
from zrp.gap.dynamics.data import TorqueLog

__all__ = ["HiddenDynamics", "Run", "Servo", "add_point_mass", "run_servo", "simulate",
           "true_model"]

#: Velocity scale of the hidden Stribeck bump's sign, rad/s (not the diagnosis's V_EPS).
TRUTH_V_EPS = 0.02


def _zeros() -> F64:
    return np.zeros(0)


@dataclass(frozen=True)
class HiddenDynamics:
    """What the real arm has and its model lacks; per-joint arrays of shape (n,) or empty."""

    coulomb: F64 = field(default_factory=_zeros)
    viscous: F64 = field(default_factory=_zeros)
    stribeck: F64 = field(default_factory=_zeros)
    stribeck_speed: float = 0.08
    armature: F64 = field(default_factory=_zeros)
    offset: F64 = field(default_factory=_zeros)
    gain: F64 = field(default_factory=_zeros)
    payload_kg: float = 0.0
    payload_offset_m: F64 = field(default_factory=lambda: np.zeros(3))
    inertial: dict[int, F64] = field(default_factory=dict)

    def per_joint(self, name: str, n: int) -> F64:
        v = np.asarray(getattr(self, name), dtype=float)
        return np.zeros(n) if v.size == 0 else v


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


def add_point_mass(phi: F64, mass: float, r: F64) -> F64:
    """phi_b plus a point mass at r (body frame, m) (eq. R1)."""
    rr = float(r @ r)
    return phi + mass * np.array([1.0, *r, rr - r[0] ** 2, rr - r[1] ** 2, rr - r[2] ** 2,
                                  -r[0] * r[1], -r[0] * r[2], -r[1] * r[2]])


def true_model(arm: Arm, hidden: HiddenDynamics) -> mujoco.MjModel:
    """A copy of the arm's model with the hidden effects (all but Stribeck and the sensor)."""
    m = copy.deepcopy(arm.model)
    n = arm.n
    m.dof_frictionloss[:] += hidden.per_joint("coulomb", n)
    m.dof_damping[:] += hidden.per_joint("viscous", n)
    m.dof_armature[:] += hidden.per_joint("armature", n)
    for b, dphi in hidden.inertial.items():
        set_body_params(m, b, body_params(m, b) + dphi)
    if hidden.payload_kg:
        b = arm.tool_body
        r = arm.tool_point + hidden.payload_offset_m
        set_body_params(m, b, add_point_mass(body_params(m, b), hidden.payload_kg, r))
    return m


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


def run_servo(plant: mujoco.MjModel, nominal: mujoco.MjModel, servo: Servo, command: Fourier,
              duration_s: float, rate_hz: float = 1000.0, substeps: int = 4,
              stribeck: tuple[F64, float] | None = None) -> Run:
    """Drive ``plant`` along ``command`` with ``servo`` (feed-forward from ``nominal``)."""
    dt = 1.0 / (rate_hz * substeps)
    p = _plant(plant, dt)
    d = mujoco.MjData(p)
    dn = mujoco.MjData(nominal)
    steps = round(duration_s * rate_hz)
    t = np.arange(steps) / rate_hz
    tf = np.arange(steps * substeps) * dt
    qc, qcd, qcdd = command.evaluate(tf)
    d.qpos[:] = qc[0]
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


def simulate(arm: Arm, hidden: HiddenDynamics, command: Fourier, duration_s: float, *,
             noise_nm: F64, servo: Servo | None = None, rate_hz: float = 1000.0,
             encoder_noise_rad: float = 1e-5, seed: int = 0) -> TorqueLog:
    """The log of the real arm (with ``hidden``) driven along ``command``: measured torques
    (1 + gain) tau + offset + N(0, noise_nm^2), positions with encoder noise, velocities."""
    rng = np.random.default_rng(seed)
    n = arm.n
    servo = servo or Servo.tuned(arm, command.q0)
    fs = hidden.per_joint("stribeck", n)
    run = run_servo(true_model(arm, hidden), arm.model, servo, command, duration_s, rate_hz,
                    stribeck=(fs, hidden.stribeck_speed) if np.any(fs) else None)
    noise = np.broadcast_to(np.asarray(noise_nm, dtype=float), (n,))
    tau = ((1.0 + hidden.per_joint("gain", n)) * run.tau + hidden.per_joint("offset", n)
           + rng.normal(size=run.tau.shape) * noise)
    q = run.q + rng.normal(size=run.q.shape) * encoder_noise_rad
    return TorqueLog(run.t, q, run.qd.copy(), tau, run.qc, None,
                     np.arange(2, run.t.size + 2), f"simulated {arm.name}", "tau")
