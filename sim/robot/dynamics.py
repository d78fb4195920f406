"""Dynamic playback: position servos track a joint trajectory under gravity.

The joint trajectory (e.g. from the nominal inverse kinematics) is fed, linearly interpolated at
every simulation step, as the set point of one MuJoCo position actuator per joint. The arm's
end-effector path is compared with the kinematic one (the same model's direct kinematics of the
commanded joints): the difference is the tracking error the servos add to the geometric error.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike
from tqdm import tqdm

from mjcf import MJCFOptions, build
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, forward_kinematics
from zrp.model.manipulator import Manipulator
from zrp.rotations import rotation_angle

__all__ = ["DynamicPlayback", "check_timed_q", "default_dynamic_options",
           "dynamic_playback"]



def check_timed_q(model: Manipulator, t: ArrayLike, q: ArrayLike) -> tuple[F64, F64]:
    """Joint values sampled at times, checked: ``t`` finite and strictly increasing, s, shape
    (N,) with N >= 2, and ``q`` (:func:`~zrp.kinematics.check_q`), shape (N, n). Returns
    (t, q) as float arrays."""
    q = check_q(model, q)
    t = np.asarray(t, dtype=float)
    if q.ndim != 2 or t.shape != (q.shape[0],) or len(t) < 2:
        raise InputError(f"t, q: expected shapes (N,) and (N, {model.n}) with N >= 2, got "
                         f"{t.shape} and {q.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("t: expected finite, strictly increasing times (s)")
    return t, q


def default_dynamic_options(model: Manipulator, **overrides: object) -> MJCFOptions:
    """Options for dynamic playback: PUMA 560 inertias for a 6R arm, rods otherwise, servos."""
    inertia = "puma560" if model.n == 6 and not model.prismatic.any() else "rods"
    kw: dict[str, object] = {"inertia": inertia, "actuators": True, "kp": 4000.0, "kv": 150.0}
    kw.update(overrides)
    return MJCFOptions(**kw)  # type: ignore[arg-type]


@dataclass(frozen=True, eq=False)
class DynamicPlayback:
    """Result of :func:`dynamic_playback` (sampled at the trajectory times).

    Attributes:
        t: sample times, s, shape (N,).
        q_command: commanded joint values, shape (N, n) (rad; model unit for prismatic).
        q_actual: simulated joint values, shape (N, n).
        position_kinematic: p from direct kinematics of ``q_command``, model unit, shape (N, 3).
        position_dynamic: p of the simulated arm, model unit, shape (N, 3).
        tracking_error: |position_dynamic - position_kinematic|, model unit, shape (N,).
        orientation_error: angle between the two hand frames, rad, shape (N,).
        length_unit: the model's length unit.
        options: the MJCF options used (gains, inertias, gravity).
        velocity_feedforward: whether the reference joint rates were fed to the servos.
    """

    t: F64
    q_command: F64
    q_actual: F64
    position_kinematic: F64
    position_dynamic: F64
    tracking_error: F64
    orientation_error: F64
    length_unit: str
    options: MJCFOptions
    velocity_feedforward: bool = True

    def __post_init__(self) -> None:
        n_t = np.asarray(self.t).shape
        if len(n_t) != 1 or np.asarray(self.tracking_error).shape != n_t \
                or np.asarray(self.position_dynamic).shape != (*n_t, 3) \
                or np.asarray(self.q_actual).shape != np.asarray(self.q_command).shape:
            raise InputError("DynamicPlayback: inconsistent array shapes (expected t (N,), "
                             "tracking_error (N,), positions (N, 3), q (N, n))")

    @property
    def max_tracking_error(self) -> float:
        """Largest end-effector tracking error, model length unit."""
        return float(np.max(self.tracking_error))

    @property
    def rms_tracking_error(self) -> float:
        return float(np.sqrt(np.mean(self.tracking_error**2)))

    def summary(self) -> str:
        o = self.options
        return (f"dynamic playback ({o.inertia} inertias, kp={o.kp:g}, kv={o.kv:g}, gravity "
                f"{'compensated' if o.gravity_compensation else 'on'}, rate feedforward "
                f"{'on' if self.velocity_feedforward else 'off'}): end-effector tracking "
                f"error max {self.max_tracking_error:.4g} {self.length_unit}, rms "
                f"{self.rms_tracking_error:.4g} {self.length_unit}, orientation max "
                f"{np.max(self.orientation_error):.3g} rad")


def dynamic_playback(
    model: Manipulator,
    t: ArrayLike,
    q: ArrayLike,
    *,
    options: MJCFOptions | None = None,
    settle_s: float = 1.0,
    velocity_feedforward: bool = True,
    progress: bool = False,
) -> DynamicPlayback:
    """Simulate position servos tracking ``q(t)`` under gravity.

    Args:
        model: the ZRP model (nominal or perturbed).
        t: strictly increasing sample times, s, shape (N,).
        q: joint set points at ``t``, shape (N, n).
        options: MJCF build options (must have ``actuators=True``); default
            :func:`default_dynamic_options`.
        settle_s: time the servos hold q[0] before t[0] (so the start is at rest), s.
        velocity_feedforward: feed the reference joint rates (finite differences of ``q``) to
            the rate servos; False = plain position servo with damping kv.
        progress: show a tqdm bar.
    """
    t, q = check_timed_q(model, t, q)
    if not (np.isfinite(settle_s) and settle_s >= 0):
        raise InputError(f"settle_s: expected a time >= 0 (s), got {settle_s!r}")
    options = options or default_dynamic_options(model)
    if not options.actuators:
        raise InputError("options.actuators: dynamic playback needs position actuators "
                         "(MJCFOptions(actuators=True))")
    arm = build(model, options)
    m = arm.model
    d = mujoco.MjData(m)
    qpos_cmd = arm.qpos(q)
    d.qpos[arm.qpos_adr] = qpos_cmd[0]
    n = model.n
    has_rate = m.nu == 2 * n  # actuators: n position servos, then n rate servos (mjcf.build)
    qdot_cmd = np.gradient(qpos_cmd, t, axis=0) if velocity_feedforward else np.zeros_like(q)
    dt = m.opt.timestep
    d.ctrl[:n] = qpos_cmd[0]
    for _ in range(round(settle_s / dt)):
        mujoco.mj_step(m, d)
    q_act = np.empty_like(q)
    pos = np.empty((len(t), 3))
    frame = np.empty((len(t), 3, 3))
    sim_t = t[0]

    def record(i: int) -> None:
        mujoco.mj_kinematics(m, d)
        q_act[i] = arm.q_from_qpos(d.qpos[arm.qpos_adr])
        pos[i] = d.site_xpos[arm.site_id] / arm.scale
        frame[i] = d.site_xmat[arm.site_id].reshape(3, 3)

    record(0)
    bar = tqdm(total=len(t) - 1, desc="dynamic playback", unit="sample", disable=not progress)
    for i in range(1, len(t)):
        while sim_t < t[i] - 1e-12:
            s = min(max((sim_t + dt - t[i - 1]) / (t[i] - t[i - 1]), 0.0), 1.0)
            d.ctrl[:n] = (1 - s) * qpos_cmd[i - 1] + s * qpos_cmd[i]
            if has_rate:
                d.ctrl[n:] = (1 - s) * qdot_cmd[i - 1] + s * qdot_cmd[i]
            mujoco.mj_step(m, d)
            sim_t += dt
        record(i)
        bar.update(1)
    bar.close()
    fk = forward_kinematics(model, q)
    err = np.linalg.norm(pos - fk.position, axis=-1)
    rot = rotation_angle(frame, fk.hand_frame)
    return DynamicPlayback(t, q, q_act, fk.position, pos, err, rot, model.length_unit, options,
                           velocity_feedforward)
