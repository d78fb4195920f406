"""The real robot's position servos, tuned per arm from its own inertia over its workspace.

Each joint k has a PD servo with integral action (the position and rate actuators of
:mod:`sim.robot.model`, the trim of :class:`sim.robot.real.Session`). Its gains come from the
inertia the joint's motor sees, the diagonal M_kk(q) of the joint-space mass matrix (armature
and payload included), sampled at q = 0 and at seeded random postures within the poses the
robot is commanded to:

    I_k = max_q M_kk(q)                                                       (eq S1)
    kp_k = max(omega^2 I_k, omega d_k)
                                (1 / c_k for a joint with compliance c_k)     (eq S2)
    kv_k = max(0, 2 zeta sqrt(kp_k I_k) - d_k)                                (eq S3)
    ki_k = min(0.15 omega, 0.5 (kv_k + d_k) / I_k)                            (eq S4)
    dt  = min(1 ms, 0.4 min_k sqrt(min_q M_kk(q) / kp_k))                     (eq S5)

An arm read from its own file often gives no rotor inertia (URDF has no such field) or a
placeholder, yet a geared drive reflects a rotor inertia of the order of its link's (the PUMA
560's drives: 0.2-1.6x their links' at joints 1-3, more at the wrist), and the motor side of a
joint with backlash needs it (with 1e-3 kg m^2 against a UR5 shoulder's 5 kg m^2 the motor
chatters on the flank and never settles). So for such arms

    armature_k = max(given_k, ROTOR_SHARE max_q M_kk,link(q))                 (eq S0)

with M_kk,link the link-side inertia (the diagonal without the armature); eqs S1-S5 then see
it.

omega (rad/s) is the chosen servo bandwidth and zeta the damping ratio: with I_k the largest
inertia, every posture has a natural frequency >= omega and a damping ratio >= zeta. The
joint's own viscous damping d_k (the file's) is part of the servo's damping: the rate gain
supplies the rest, and a joint whose own damping is heavier than omega I_k gets the stiffness
omega d_k, so that its slow (overdamped) pole d_k / kp_k is still at omega (without it, an
xArm7 wrist with d = 2 N m s/rad against I ~ 1e-3 kg m^2 crept to its target over seconds).
The integral rate is 0.15 omega for every joint (the servo's own speed for a joint tuned by
omega^2 I_k; a stiffened joint's sqrt(kp / I) would make the integral, updated every control
period, unstable). ki is the
integral rate (1/s: trim += ki dt error); the servo I s^3 + kv s^2 + kp s + kp ki is stable for
ki < kv / I (Routh), so eq S4 keeps half of that margin at every posture (I <= I_k). The
explicit integrator is stable for dt well below sqrt(I / kp) (eq S5).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from zrp.arrays import F64

__all__ = ["INTEGRAL_SHARE", "ROTOR_SHARE", "ServoGains", "rotor_armature", "servo_inertias",
           "tune_servos"]

#: ki / omega of eq S4 (the integral action's speed relative to the servo's).
INTEGRAL_SHARE = 0.15
#: the least rotor inertia of eq S0 as a share of the link-side inertia.
ROTOR_SHARE = 0.5


@dataclass(frozen=True, eq=False)
class ServoGains:
    """Per-joint servo gains (eqs S1-S5), shape (n,) each.

    Attributes:
        kp: stiffness, N m/rad (N/m).
        kv: damping, N m s/rad (N s/m).
        ki: integral rate, 1/s.
        inertia_max: I_k of eq S1, kg m^2 (kg).
        inertia_min: min_q M_kk(q), kg m^2 (kg).
        timestep: simulation step of eq S5 (or the one asked for), s.
    """

    kp: F64
    kv: F64
    ki: F64
    inertia_max: F64
    inertia_min: F64
    timestep: float


def servo_inertias(probe: mujoco.MjModel, motor: Sequence[str], lower: F64, upper: F64,
                   poses: int = 64) -> F64:
    """M_kk at each motor joint, at q = 0 (row 0) and at ``poses - 1`` seeded random postures
    within ``lower``..``upper`` (rad, m), shape (poses, n), kg m^2 (kg)."""
    d = mujoco.MjData(probe)
    ids = [mujoco.mj_name2id(probe, mujoco.mjtObj.mjOBJ_JOINT, nm) for nm in motor]
    adr = [probe.jnt_qposadr[j] for j in ids]
    dof = [probe.jnt_dofadr[j] for j in ids]
    rng = np.random.default_rng(0)
    full = np.zeros((probe.nv, probe.nv))
    out = np.empty((poses, len(adr)))
    for i in range(poses):
        d.qpos[:] = probe.qpos0
        if i:
            d.qpos[adr] = rng.uniform(lower, upper)
        mujoco.mj_forward(probe, d)
        mujoco.mj_fullM(probe, d, full)
        out[i] = full[dof, dof]
    return out


def rotor_armature(probe: mujoco.MjModel, motor: Sequence[str], given: F64, lower: F64,
                   upper: F64) -> F64:
    """Eq S0: each motor joint's armature, kg m^2 (kg), shape (n,), from the compiled
    ``probe`` (whose motor joints carry their current armature) and the file's ``given``."""
    ids = [mujoco.mj_name2id(probe, mujoco.mjtObj.mjOBJ_JOINT, nm) for nm in motor]
    current = probe.dof_armature[[probe.jnt_dofadr[j] for j in ids]]
    link = servo_inertias(probe, motor, lower, upper).max(axis=0) - current
    return np.maximum(np.asarray(given, dtype=float), ROTOR_SHARE * link)


def tune_servos(probe: mujoco.MjModel, motor: Sequence[str], compliance: Mapping[int, float],
                bandwidth: float, damping_ratio: float, lower: F64, upper: F64,
                timestep: float | None = None) -> ServoGains:
    """Gains of eqs S1-S5 for the motor joints ``motor`` of the compiled ``probe`` (their
    ``damping`` is the joint's own, d_k).

    Args:
        compliance: 1-based joint -> c (rad/(N m)): that joint's stiffness is 1/c (eq S2).
        bandwidth: omega, rad/s.
        damping_ratio: zeta.
        lower, upper: the postures sampled (rad; slides in m), shape (n,) each.
        timestep: s; None: eq S5.
    """
    inertia = servo_inertias(probe, motor, lower, upper)
    i_max, i_min = inertia.max(axis=0), inertia.min(axis=0)
    ids = [mujoco.mj_name2id(probe, mujoco.mjtObj.mjOBJ_JOINT, nm) for nm in motor]
    own = probe.dof_damping[[probe.jnt_dofadr[j] for j in ids]]
    kp = np.maximum(bandwidth**2 * i_max, bandwidth * own)
    for k, c in compliance.items():
        kp[k - 1] = 1.0 / c
    total = 2.0 * damping_ratio * np.sqrt(kp * i_max)
    kv = np.maximum(0.0, total - own)
    ki = np.minimum(INTEGRAL_SHARE * bandwidth, 0.5 * (kv + own) / i_max)
    dt = timestep if timestep is not None else \
        float(min(1e-3, 0.4 * np.min(np.sqrt(i_min / kp))))
    return ServoGains(kp, kv, ki, i_max, i_min, dt)
