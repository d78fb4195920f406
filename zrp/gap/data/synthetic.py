"""Synthetic measurements with known injected effects (for tests, examples and benchmarks).

The injection goes through the toolkit's forward kinematics (:func:`zrp.forward_kinematics` of
a perturbed :class:`~zrp.Manipulator` at perturbed joint values), not through the diagnosis's
own corrected-model code, so that recovering the injection checks more than self-consistency.
The physically simulated counterpart (MuJoCo) is the blind benchmark's job.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements
from zrp.kinematics.forward import check_q, forward_kinematics
from zrp.kinematics.identification import axis_tangents, tilt_axes
from zrp.model.manipulator import Manipulator
from zrp.rotations import matrix_from_rotvec
from zrp.units import G_STANDARD, metres_per_unit

__all__ = ["Injection", "synthesize"]



@dataclass(frozen=True)
class Injection:
    """Effects to inject, keyed by 1-based joint (or body vector for ``link``).

    Attributes:
        joint_offset: rad (length unit for prismatic joints) per joint.
        encoder_scale: dimensionless scale error per joint (q_actual = q (1 + s)).
        backlash: the full play b per joint, rad (as in ``zrp measure`` and ``zrp diagnose``);
            the joint lags by b/2 against its direction of approach.
        backlash_gravity: the full play b per joint, rad; the joint rests b/2 off centre on
            the side of its play that the gravity torque of ``masses`` pushes it to.
        backlash_friction: N m per joint (with ``backlash``): where the gravity torque of
            ``masses`` exceeds it, the joint rests on the loaded flank instead of lagging
            against its approach direction.
        backlash_lead: joints (with ``backlash``) that the approach leaves b/2 ahead, on the
            leading flank, instead of lagging (eq. B1 of :mod:`zrp.gap.fit.profiles`).
        cyclic_error: per joint, (harmonic h, sin amplitude rad, cos amplitude rad).
        compliance: rad per (N m) per joint; deflection = c tau with tau the gravity torque of
            the point masses ``masses``.
        masses: kg at mass points: "p{k}" (point on joint k) or "ee".
        link: body-vector corrections (length unit), shape (3,) per body index 1..n+1.
        tilt: axis tilts (rad) towards the tangents t1, t2 (zrp.manufacturing.axis_tangents).
        thermal: kappa, 1/deg C (bodies scale by 1 + kappa (temp - t_ref)).
        t_ref: reference temperature, deg C.
        sag: length unit; every tool point sags along the base -z by
            ``sag sin(q2) cos(q3)`` (actual joint values): a bending of the arm with a shape
            no effect in the library has, to test what the diagnosis says remains.
    """

    joint_offset: Mapping[int, float] = field(default_factory=dict)
    encoder_scale: Mapping[int, float] = field(default_factory=dict)
    backlash: Mapping[int, float] = field(default_factory=dict)
    backlash_gravity: Mapping[int, float] = field(default_factory=dict)
    backlash_friction: Mapping[int, float] = field(default_factory=dict)
    backlash_lead: frozenset[int] = frozenset()
    cyclic_error: Mapping[int, tuple[int, float, float]] = field(default_factory=dict)
    compliance: Mapping[int, float] = field(default_factory=dict)
    masses: Mapping[str, float] = field(default_factory=lambda: {"p3": 8.0, "p5": 4.0,
                                                                 "ee": 3.0})
    link: Mapping[int, tuple[float, float, float]] = field(default_factory=dict)
    tilt: Mapping[int, tuple[float, float]] = field(default_factory=dict)
    thermal: float = 0.0
    t_ref: float = 20.0
    sag: float = 0.0


def _gravity_torque(model: Manipulator, q: F64, masses: Mapping[str, float],
                    g_dir: F64) -> F64:
    """tau[p, k] = sum_j m_j g u_k . ((P_j - p_k) x g_dir) * s, N m, shape (P, n); s metres
    per length unit (1e-3 for mm, 1 for m: the same arm gives the same torque in any unit)."""
    to_m = metres_per_unit(model.length_unit, "model.length_unit")
    fk = forward_kinematics(model, q)
    tau = np.zeros(q.shape)
    for lab, m in masses.items():
        if lab == "ee":
            pt, owner = fk.position, model.n
        else:
            j = int(lab[1:]) - 1
            pt, owner = fk.points[:, j], j
        for k in range(model.n):
            if k < owner and not model.prismatic[k]:
                arm = np.cross(pt - fk.points[:, k], g_dir)
                tau[:, k] += m * G_STANDARD * to_m * np.einsum("pi,pi->p", fk.axes[:, k], arm)
    return tau


def _approach(q: F64) -> F64:
    """Direction from which each joint approached each pose (the measurement order)."""
    d = np.zeros_like(q)
    for i in range(1, q.shape[0]):
        s = np.sign(q[i] - q[i - 1])
        d[i] = np.where(s != 0, s, d[i - 1])
    return d


def _actual_joint_values(model: Manipulator, q: F64, inj: Injection) -> F64:
    """The joint values the "real" robot reaches when ``q`` is commanded."""
    qa = q.copy()
    for k, v in inj.joint_offset.items():
        qa[:, k - 1] += v
    for k, v in inj.encoder_scale.items():
        qa[:, k - 1] += v * q[:, k - 1]
    g_dir = np.array([0.0, 0.0, -1.0])
    if inj.backlash:
        d = _approach(q)
        tau_b = _gravity_torque(model, q, inj.masses, g_dir)
        for k, v in inj.backlash.items():
            f = inj.backlash_friction.get(k, np.inf)
            t = tau_b[:, k - 1]
            side = 1.0 if k in inj.backlash_lead else -1.0
            qa[:, k - 1] += 0.5 * v * np.where(np.abs(t) > f, np.sign(t), side * d[:, k - 1])
    for k, (h, a, b) in inj.cyclic_error.items():
        qa[:, k - 1] += a * np.sin(h * q[:, k - 1]) + b * np.cos(h * q[:, k - 1])
    if inj.compliance or inj.backlash_gravity:
        tau = _gravity_torque(model, q, inj.masses, g_dir)
        for k, c in inj.compliance.items():
            qa[:, k - 1] += c * tau[:, k - 1]
        for k, b in inj.backlash_gravity.items():
            qa[:, k - 1] += 0.5 * b * np.sign(tau[:, k - 1])
    return qa


def _actual_model(model: Manipulator, inj: Injection) -> tuple[F64, F64]:
    """Axes (n, 3) and bodies (n + 1, 3) of the "real" robot (tilts and link errors)."""
    bodies = np.array(model.bodies, dtype=float)
    for k, db in inj.link.items():
        bodies[k - 1] += np.asarray(db, dtype=float)
    tilts = np.zeros((model.n, 2))
    for k, tv in inj.tilt.items():
        tilts[k - 1] = tv
    return tilt_axes(model.axes, axis_tangents(model.axes), tilts), bodies


def _tool_points(model: Manipulator, qa: F64, inj: Injection, t: F64,
                 temp: F64 | None) -> F64:
    """Tool points of the "real" robot in its base frame, shape (P, M, 3)."""
    axes, bodies = _actual_model(model, inj)
    if inj.thermal and temp is not None:
        pts = np.empty((qa.shape[0], t.shape[0], 3))
        for i in range(qa.shape[0]):
            s = 1.0 + inj.thermal * (temp[i] - inj.t_ref)
            fk = forward_kinematics(model.with_arrays(axes=axes, bodies=bodies * s), qa[i])
            pts[i] = fk.position + t @ fk.rotation.T
        return pts
    fk = forward_kinematics(model.with_arrays(axes=axes, bodies=bodies), qa)
    return fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, t)


def synthesize(model: Manipulator, q: ArrayLike, injection: Injection, *,
               rng: np.random.Generator, noise_sigma: float = 0.02,
               tool_offsets: ArrayLike = ((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0),
                                          (0.0, -70.0, 40.0)),
               base_rotvec: ArrayLike = (0.02, -0.01, 0.8),
               base_translation: ArrayLike = (1500.0, -300.0, 200.0),
               frame: str = "instrument", temp: ArrayLike | None = None) -> Measurements:
    """Measurements of the "real" robot = ``model`` with ``injection`` applied.

    Args:
        q: commanded joint values in measurement order, rad, shape (P, n).
        injection: the effects.
        rng: noise (and nothing else) is drawn from it.
        noise_sigma: isotropic Gaussian noise per coordinate, length unit.
        tool_offsets: t_j per tool point, zero-reference base frame, shape (M, 3).
        base_rotvec, base_translation: instrument-from-base transform (ignored for "base").
        temp: temperature per pose, deg C, shape (P,) (required for ``thermal``).

    Returns:
        Measurements with M rows per pose (points "s1".."sM").
    """
    q = np.array(check_q(model, q), dtype=float)
    if q.ndim != 2:
        raise InputError(f"q: expected shape (P, {model.n}), got {q.shape}")
    P = q.shape[0]
    if injection.thermal and temp is None:
        raise InputError("thermal injection needs temp (deg C per pose)")
    qa = _actual_joint_values(model, q, injection)
    t = np.asarray(tool_offsets, dtype=float)
    temp_arr = None if temp is None else np.asarray(temp, dtype=float)
    pts = _tool_points(model, qa, injection, t, temp_arr)
    if injection.sag:
        pts[:, :, 2] -= (injection.sag * np.sin(qa[:, 1]) * np.cos(qa[:, 2]))[:, None]
    if frame == "instrument":
        rb = matrix_from_rotvec(base_rotvec)
        pts = pts @ rb.T + np.asarray(base_translation, dtype=float)
    pts = pts + rng.normal(scale=noise_sigma, size=pts.shape)
    M = t.shape[0]
    return Measurements.from_arrays(
        np.repeat(np.arange(P), M), np.repeat(q, M, axis=0), pts.reshape(-1, 3),
        point=np.tile([f"s{j + 1}" for j in range(M)], P), frame=frame,
        temp=None if temp_arr is None else np.repeat(temp_arr, M))
