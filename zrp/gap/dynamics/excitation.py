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

Work is bounded before anything is allocated: at most :data:`MAX_HARMONICS` harmonics,
:data:`MAX_CANDIDATES` random starts and :data:`MAX_ITERATIONS` steps; each evaluation takes
max(200, 20 L) samples of one period (400 and 40 L for the torques).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from zrp.arguments import check_float, check_int
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.fourier import (
    MAX_HARMONICS,
    Fourier,
    _rest_projector,
    random_fourier,
    scale_into,
)
from zrp.gap.dynamics.inertia import V_EPS, base_directions
from zrp.limits import MAX_DESIGN_CANDIDATES as MAX_CANDIDATES
from zrp.limits import MAX_DESIGN_ITERATIONS as MAX_ITERATIONS

__all__ = ["MAX_CANDIDATES", "MAX_HARMONICS", "MAX_ITERATIONS", "Excitation",
           "condition_number", "design_excitation", "structural_rank", "within_torque"]



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


def condition_number(arm: Arm, f: Fourier, samples: int | None = None,
                     basis: tuple[F64, F64] | None = None, rank: int | None = None) -> float:
    """kappa of eq. X2 along one period of ``f`` (``samples``: default max(200, 20 L)): the
    largest over the ``rank``-th singular value (``rank``: :func:`structural_rank`)."""
    samples = samples or max(200, 20 * f.a.shape[1])
    basis = basis or base_directions(arm)
    a = _identification_matrix(arm, f, basis, samples)
    norms = np.linalg.norm(a, axis=0)
    if np.any(norms == 0.0):
        return float("inf")
    s = np.linalg.svd(a / norms, compute_uv=False)
    r = rank or structural_rank(arm, basis)
    return float(s[0] / s[r - 1]) if s[r - 1] > 0 else float("inf")


def within_torque(arm: Arm, f: Fourier, limit: F64, t: F64 | None = None
                  ) -> tuple[Fourier, F64]:
    """``f``, shrunk about q0 by steps of 10 % (at most 40) until the model's torques at the
    times ``t`` (default: max(400, 40 L) samples of one period) stay within ``limit``, and
    those torques (S, n)."""
    if t is None:
        t = np.linspace(0.0, 1.0 / f.f0_hz, max(400, 40 * f.a.shape[1]), endpoint=False)
    for _ in range(40):
        tau = arm.inverse_dynamics(*f.evaluate(t))
        if np.all(np.abs(tau) <= limit):
            return f, tau
        f = Fourier(f.q0, 0.9 * f.a, 0.9 * f.b, f.f0_hz)
    k = int(np.argmax(np.abs(tau).max(0) / limit))
    raise InputError(f"torque_limit: even a small exciting motion needs more torque than the "
                     f"limits allow (joint {k + 1}: {np.abs(tau[:, k]).max():.4g} over "
                     f"{limit[k]:.4g}; gravity alone at q0?); choose another posture q0")


def _within_torque(arm: Arm, f: Fourier, limit: F64) -> tuple[Fourier, F64]:
    f, tau = within_torque(arm, f, limit)
    return f, np.abs(tau).max(0)


def _positive(value: object, n: int, field: str, *, finite: bool = True) -> F64:
    try:
        v = np.broadcast_to(np.asarray(value, dtype=float), (n,))
    except (TypeError, ValueError):
        raise InputError(f"{field}: expected 1 or {n} numbers > 0, got {value!r}") from None
    bad = np.isnan(v) | (v <= 0) | (~np.isfinite(v) if finite else False)
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(f"{field}: joint {k + 1} is {v[k]!r}; expected a "
                         f"{'finite ' if finite else ''}number > 0")
    return v


def _check_inputs(arm: Arm, q0: F64, harmonics: int, f0_hz: float, candidates: int,
                  iterations: int, step: float) -> F64:
    """q0 (n,), finite, within the position limits; the bounded sizes (module docstring)."""
    check_int(harmonics, "harmonics", 2, MAX_HARMONICS)
    check_int(candidates, "candidates", 1, MAX_CANDIDATES)
    check_int(iterations, "iterations", 0, MAX_ITERATIONS)
    check_float(f0_hz, "f0_hz", 0.0, open_lo=True, unit="Hz")
    check_float(step, "step", 0.0, 10.0, open_lo=True)
    q0 = np.asarray(q0, dtype=float)
    if q0.shape != (arm.n,) or not np.all(np.isfinite(q0)):
        raise InputError(f"q0: expected {arm.n} finite joint values, got {q0!r}")
    return q0


def _check_envelope(arm: Arm, q0: F64, q_amp: F64) -> None:
    lo, hi = arm.position_limits()
    bad = (q0 - q_amp < lo) | (q0 + q_amp > hi)
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(f"q0, q_amp: joint {k + 1} would move over [{q0[k] - q_amp[k]:.6g}, "
                         f"{q0[k] + q_amp[k]:.6g}], beyond its position limits "
                         f"[{lo[k]:.6g}, {hi[k]:.6g}]")


def design_excitation(arm: Arm, q0: F64, q_amp: F64 | float, qd_max: F64 | float,
                      qdd_max: F64 | float, *, torque_limit: F64 | None = None,
                      harmonics: int = 5, f0_hz: float = 0.1, candidates: int = 8,
                      iterations: int = 20, step: float = 0.2, seed: int = 0,
                      progress: Callable[[int, int], None] | None = None) -> Excitation:
    """Design the exciting command (module docstring); limits per joint (or one for all).
    ``progress(done, total)`` is called after each start and each step.

    Raises:
        InputError: q0 not n finite values, q0 +- q_amp beyond the arm's position limits, a
            limit that is not a finite number > 0 (torque: inf allowed), harmonics,
            candidates or iterations beyond their bounds, or torque limits that even a small
            motion exceeds.
    """
    n = arm.n
    q0 = _check_inputs(arm, q0, harmonics, f0_hz, candidates, iterations, step)
    lims = [_positive(v, n, f) for v, f in ((q_amp, "q_amp"), (qd_max, "qd_max"),
                                            (qdd_max, "qdd_max"))]
    _check_envelope(arm, q0, lims[0])
    tlim = _positive(arm.torque_limits() if torque_limit is None else torque_limit, n,
                     "torque_limit", finite=False)
    basis = base_directions(arm)
    rank = structural_rank(arm, basis)
    rng = np.random.default_rng(seed)

    def fit(f: Fourier) -> tuple[Fourier, float]:
        f, _ = _within_torque(arm, scale_into(f, *lims), tlim)
        return f, condition_number(arm, f, basis=basis, rank=rank)

    tick = progress or (lambda done, total: None)
    total = candidates + iterations
    starts = []
    for k in range(candidates):
        starts.append(fit(random_fourier(q0, *lims, harmonics=harmonics, f0_hz=f0_hz, seed=rng)))
        tick(k + 1, total)
    best, kappa = min(starts, key=lambda s: s[1])
    kappa_start = kappa
    for k in range(iterations):
        tick(candidates + k + 1, total)
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
