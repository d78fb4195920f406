"""Exciting trajectory design: a finite Fourier series (:mod:`zrp.gap.dynamics.fourier`, eq. X1)
within position, velocity, acceleration and torque limits that minimises the condition number
of the identification regressor (eq. X2)::

    kappa = cond([Y_base V | coulomb | viscous | armature | offset] W)

over samples of one period (Y_base V: the identifiable inertial combinations, eq. R4; W scales
each column to unit norm, so kappa does not depend on units). A low kappa means every
parameter is seen independently of the others (Swevers et al. 1997; Gautier & Khalil 1992).

The search is a seeded random search over ``candidates`` series followed by ``iterations``
steps of stochastic hill climbing on the best one (each step perturbs all coefficients by
``step`` of their size, re-scales into the limits and keeps the result if kappa drops). It is
not a global optimum; it reports the kappa it reached and the random start's for comparison.
Torque limits (the model's actuator force ranges, or ``torque_limit``) are met by shrinking
the series until the nominal model's torques stay inside them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.fourier import Fourier, _rest_projector, random_fourier, scale_into
from zrp.gap.dynamics.inertia import V_EPS, base_directions

__all__ = ["Excitation", "condition_number", "design_excitation", "structural_rank"]


@dataclass(frozen=True)
class Excitation:
    """The designed command, its kappa (eq. X2), the best random start's, and its peaks."""

    command: Fourier
    kappa: float
    kappa_start: float
    peak_torque: F64


def _identification_matrix(arm: Arm, f: Fourier, basis: tuple[F64, F64], samples: int) -> F64:
    t = np.linspace(0.0, 1.0 / f.f0_hz, samples, endpoint=False)
    return _matrix_at(arm, *f.evaluate(t), basis)


def _matrix_at(arm: Arm, q: F64, qd: F64, qdd: F64, basis: tuple[F64, F64]) -> F64:
    y, _ = arm.regressor(q, qd, qdd)
    v, scale = basis
    blocks = [(y * scale) @ v]
    n = arm.n
    for col in (np.tanh(qd / V_EPS), qd, qdd, np.ones_like(qd)):
        per = np.zeros((*qd.shape, n))
        per[:, np.arange(n), np.arange(n)] = col
        blocks.append(per)
    return np.concatenate(blocks, axis=-1).reshape(-1, sum(b.shape[-1] for b in blocks))


def structural_rank(arm: Arm, basis: tuple[F64, F64], seed: int = 0) -> int:
    """How many independent columns eq. X2's matrix can have at all (random states): some
    are exactly dependent for every motion (joint 1's armature is link 1's inertia about
    joint 1's axis), and kappa is taken over the independent ones."""
    rng = np.random.default_rng(seed)
    n = arm.n
    q, qd, qdd = rng.uniform(-np.pi, np.pi, (60, n)), rng.normal(0, 1, (60, n)), rng.normal(
        0, 3, (60, n))
    a = _matrix_at(arm, q, qd, qdd, basis)
    s = np.linalg.svd(a / np.linalg.norm(a, axis=0), compute_uv=False)
    return int(np.sum(s > 1e-9 * s[0]))


def condition_number(arm: Arm, f: Fourier, samples: int = 200,
                     basis: tuple[F64, F64] | None = None, rank: int | None = None) -> float:
    """kappa of eq. X2 along one period of ``f``: the largest over the ``rank``-th singular
    value (``rank``: :func:`structural_rank`)."""
    basis = basis or base_directions(arm)
    a = _identification_matrix(arm, f, basis, samples)
    norms = np.linalg.norm(a, axis=0)
    if np.any(norms == 0.0):
        return float("inf")
    s = np.linalg.svd(a / norms, compute_uv=False)
    r = rank or structural_rank(arm, basis)
    return float(s[0] / s[r - 1]) if s[r - 1] > 0 else float("inf")


def _torque_limits(arm: Arm, torque_limit: F64 | None) -> F64:
    if torque_limit is not None:
        return np.broadcast_to(np.asarray(torque_limit, dtype=float), (arm.n,))
    return arm.torque_limits()


def _within_torque(arm: Arm, f: Fourier, limit: F64) -> tuple[Fourier, F64]:
    t = np.linspace(0.0, 1.0 / f.f0_hz, 400, endpoint=False)
    for _ in range(40):
        peak = np.abs(arm.inverse_dynamics(*f.evaluate(t))).max(0)
        if np.all(peak <= limit):
            return f, peak
        f = Fourier(f.q0, 0.9 * f.a, 0.9 * f.b, f.f0_hz)
    raise InputError("torque_limit: even a small exciting motion needs more torque than the "
                     "limits allow at q0 (gravity alone?); choose another posture q0")


def design_excitation(arm: Arm, q0: F64, q_amp: F64 | float, qd_max: F64 | float,
                      qdd_max: F64 | float, *, torque_limit: F64 | None = None,
                      harmonics: int = 5, f0_hz: float = 0.1, candidates: int = 8,
                      iterations: int = 20, step: float = 0.2, seed: int = 0) -> Excitation:
    """Design the exciting command (module docstring); limits per joint (or one for all)."""
    n = arm.n
    q0 = np.asarray(q0, dtype=float)
    if q0.shape != (n,):
        raise InputError(f"q0: expected {n} joint values, got shape {q0.shape}")
    lims = [np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in (q_amp, qd_max, qdd_max)]
    tlim = _torque_limits(arm, torque_limit)
    basis = base_directions(arm)
    rank = structural_rank(arm, basis)
    rng = np.random.default_rng(seed)

    def fit(f: Fourier) -> tuple[Fourier, float]:
        f, _ = _within_torque(arm, scale_into(f, *lims), tlim)
        return f, condition_number(arm, f, basis=basis, rank=rank)

    starts = [fit(random_fourier(q0, *lims, harmonics=harmonics, f0_hz=f0_hz, seed=rng))
              for _ in range(candidates)]
    best, kappa = min(starts, key=lambda s: s[1])
    kappa_start = kappa
    for _ in range(iterations):
        a = best.a * (1.0 + step * rng.normal(size=best.a.shape))
        b = best.b * (1.0 + step * rng.normal(size=best.b.shape))
        # keep the start-at-rest conditions: perturb, then project as random_fourier does
        trial = random_fourier(q0, *lims, harmonics=harmonics, f0_hz=f0_hz, seed=rng)
        trial = Fourier(q0, _project(a, b, trial)[0], _project(a, b, trial)[1], f0_hz)
        f, k = fit(trial)
        if k < kappa:
            best, kappa = f, k
    _, peak = _within_torque(arm, best, tlim)
    return Excitation(best, kappa, kappa_start, peak)


def _project(a: F64, b: F64, like: Fourier) -> tuple[F64, F64]:
    """(a, b) projected onto the start-at-rest conditions of eq. X1."""
    L = a.shape[1]
    coef = np.concatenate([a, b], axis=1) @ _rest_projector(like.omegas).T
    return coef[:, :L], coef[:, L:]
