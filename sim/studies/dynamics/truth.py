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

from mjcf.arm import Arm
from mjcf.inverse import body_params, set_body_params
from mjcf.tracking import Run, Servo, run_servo
from zrp.arrays import F64
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.fourier import Fourier
from zrp.gap.dynamics.inertia import add_point_mass

__all__ = ["HiddenDynamics", "Run", "Servo", "add_point_mass", "run_servo", "simulate",
           "true_model"]



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
