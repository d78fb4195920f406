"""Tolerance allocation: the loosest per-parameter tolerances meeting a requirement.

**Allocation.** :func:`allocate_tolerances` finds per-parameter tolerances that meet a
requirement such as "delta_p <= 0.1 mm at the 99th percentile of max_t delta_p" while keeping
them as loose as possible. *Looseness is scored with the reciprocal cost-tolerance model*:
manufacturing cost ``C = sum_i 1 / (c_i tol_i)``, where c_i = 1 for lengths (model unit) and
c_i = ``angle_scale_mm`` (default 100 mm) for angles, i.e. an angular tolerance counts like
the lateral tolerance it produces at 100 mm. The reported looseness is the harmonic mean of the
length-equivalent tolerances, ``H = P / C`` (larger is looser, i.e. cheaper). Minimising C under
a first-order root-sum-square constraint ``sum_i s_i^2 tol_i^2 = const`` gives
``tol_i ∝ (1 / (c_i s_i^2))^(1/3)`` (Lagrange), where s_i^2 is the trajectory-mean squared
sensitivity (normalised by the requirement). That shape is kept (capped at ``max_length`` /
``max_angle_rad``) and one common scale is found by bisection on the *nonlinear* Monte Carlo
percentile (common random numbers), then verified with fresh draws. The result is compared with
the equal-tolerance allocation (one length-equivalent tolerance for all) meeting the same
requirement.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.identification import ParameterSpace, parameter_jacobian, parameter_space
from zrp.manufacturing._checks import check_distribution, nonnegative, positive_int
from zrp.manufacturing.budget import Contribution, contributions, worst_case_bound
from zrp.manufacturing.population import (
    MonteCarloResult,
    monte_carlo,
    nonlinear_maxima,
    trajectory_arrays,
)
from zrp.manufacturing.tolerance import Tolerances, draw_parameters, percentile_ci
from zrp.model.manipulator import Manipulator

__all__ = ["Allocation", "allocate_tolerances"]

Arrays = tuple[F64, F64, F64, F64, F64]


@dataclass(frozen=True, eq=False)
class Allocation:
    """Result of :func:`allocate_tolerances`.

    Attributes:
        tolerances: the allocated tolerances.
        baseline: the equal-length-equivalent tolerances meeting the same requirement.
        looseness_mm, baseline_looseness_mm: harmonic mean of length-equivalent tolerances.
        requirement: {"max_delta_p", "max_angle_rad", "percentile"} (None where not required).
        verification: Monte Carlo of the allocation with fresh draws.
        verified: whether the verification met the requirement.
        ci_delta_p: 95 % confidence interval of the verified delta_p percentile.
        angle_scale_mm: weight turning rad into length-equivalent mm.
        contribution: ranked first-order contributions under the allocated tolerances.
        worst_case_p, worst_case_angle_rad: first-order worst-case bounds (max over t).
        scale_rounds: number of verification rounds (1 if the first verification passed).
    """

    tolerances: Tolerances
    baseline: Tolerances
    looseness_mm: float
    baseline_looseness_mm: float
    requirement: dict[str, float | None]
    verification: MonteCarloResult
    verified: bool
    ci_delta_p: tuple[float, float]
    angle_scale_mm: float
    contribution: Contribution
    worst_case_p: float
    worst_case_angle_rad: float
    scale_rounds: int

    def __post_init__(self) -> None:
        if not isinstance(self.tolerances, Tolerances) or not isinstance(self.baseline,
                                                                          Tolerances):
            raise InputError("Allocation: tolerances and baseline must be Tolerances")
        if not isinstance(self.verification, MonteCarloResult):
            raise InputError("Allocation.verification: expected a MonteCarloResult")

    def summary(self) -> dict[str, Any]:
        pct = float(self.requirement["percentile"] or 99.0)
        dp, ang = self.verification.percentile(pct)
        return {
            "requirement": self.requirement,
            "looseness_score": "harmonic mean of length-equivalent tolerances (mm); angles "
                               f"count as tol_rad * {self.angle_scale_mm:g} mm",
            "looseness_mm": self.looseness_mm,
            "baseline_equal_tolerance_looseness_mm": self.baseline_looseness_mm,
            "looser_than_baseline_factor": self.looseness_mm / self.baseline_looseness_mm
            if self.baseline_looseness_mm > 0 else float("inf"),
            "verified": self.verified,
            f"verified_p{pct:g}_delta_p": dp,
            f"verified_p{pct:g}_delta_p_ci95": list(self.ci_delta_p),
            f"verified_p{pct:g}_angle_rad": ang,
            "verification_robots": self.verification.n_robots,
            "first_order_worst_case_delta_p": self.worst_case_p,
            "first_order_worst_case_angle_rad": self.worst_case_angle_rad,
            "tolerances": self.tolerances.as_dict(),
            "baseline_tolerances": self.baseline.as_dict(),
        }


def _scale_to_requirement(model: Manipulator, arrays: Arrays,
                          shape: F64, caps: F64, fixed: F64, free: NDArray[np.bool_], z: F64,
                          pct: float, req_p: float | None, req_r: float | None,
                          joint_offsets: bool, rel_tol: float = 1e-4) -> float:
    """Largest alpha with percentile(max(dp/req_p, ang/req_r)) <= 1, tol = min(alpha shape, cap)
    on the free parameters (bisection in log alpha on common random numbers ``z``)."""

    def ratio(alpha: float) -> float:
        tol = np.where(free, np.minimum(alpha * shape, caps), fixed)
        dp, ang = nonlinear_maxima(model, arrays, z * tol, joint_offsets)
        r = 0.0
        if req_p is not None:
            r = max(r, float(np.percentile(dp, pct)) / req_p)
        if req_r is not None:
            r = max(r, float(np.percentile(ang, pct)) / req_r)
        return r

    r0 = ratio(0.0)
    if r0 > 1.0:
        raise InputError(f"the fixed tolerances alone violate the requirement (ratio {r0:.3g}); "
                         "loosen the requirement or tighten the fixed tolerances")
    lo, hi = 0.0, 1.0
    while ratio(hi) <= 1.0:
        lo, hi = hi, hi * 4.0
        if hi > 1e12:
            return hi  # every free tolerance sits at its cap
    if lo == 0.0:
        lo = hi
        while ratio(lo) > 1.0:
            hi, lo = lo, lo / 4.0
            if lo < 1e-18:
                raise InputError("allocation: the requirement cannot be met by any tolerance")
    for _ in range(40):
        mid = np.sqrt(lo * hi)
        if ratio(mid) <= 1.0:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.0 + rel_tol:
            break
    return lo


def _requirement(model: Manipulator, max_delta_p: float | None, max_angle_rad: float | None,
                 percentile: float) -> tuple[float | None, float | None, float]:
    """(required delta_p, required angle, percentile), checked."""
    if max_delta_p is None and max_angle_rad is None:
        raise InputError("requirement: give max_delta_p and/or max_angle_rad")
    req_p = None if max_delta_p is None else nonnegative(max_delta_p, "max_delta_p",
                                                         model.length_unit)
    req_r = None if max_angle_rad is None else nonnegative(max_angle_rad, "max_angle_rad",
                                                           "rad")
    if (req_p is not None and req_p <= 0) or (req_r is not None and req_r <= 0):
        raise InputError("requirement: max_delta_p / max_angle_rad must be > 0")
    if not 0.0 < float(percentile) < 100.0:
        raise InputError(f"percentile: expected 0 < percentile < 100, got {percentile!r}")
    return req_p, req_r, float(percentile)


def _check_search(distribution: str, angle_scale_mm: float, margin: float, n_search: int,
                  n_verify: int) -> tuple[float, int, int]:
    """(angle_scale_mm, n_search, n_verify), checked."""
    check_distribution(distribution)
    angle_scale_mm = nonnegative(angle_scale_mm, "angle_scale_mm", "mm per rad")
    if angle_scale_mm <= 0:
        raise InputError("angle_scale_mm: expected > 0")
    if not 0.0 <= margin < 0.5:
        raise InputError(f"margin: expected 0 <= margin < 0.5, got {margin!r}")
    return (angle_scale_mm, positive_int(n_search, "n_search", 100),
            positive_int(n_verify, "n_verify", 100))


def _fixed_parameters(model: Manipulator, space: ParameterSpace,
                      fixed: Mapping[str, float] | None) -> tuple[NDArray[np.bool_], F64]:
    """(mask of the free parameters, values of the fixed ones (0 where free))."""
    free = np.ones(space.size, dtype=bool)
    if not fixed:
        return free, np.zeros(space.size)
    fixed_tol = Tolerances.build(model, per_parameter=fixed)
    for pattern in fixed:
        for i, nm in enumerate(space.names):
            if fnmatch.fnmatchcase(nm, pattern):
                free[i] = False
    return free, np.where(free, 0.0, fixed_tol.values)


def _rss_shape(jac: F64, c: F64, caps: F64, req_p: float | None, req_r: float | None) -> F64:
    """tol_i proportional to (1 / (c_i s_i^2))^(1/3), s_i^2 the trajectory-mean squared
    sensitivity normalised by the requirement (insensitive parameters: far beyond the cap)."""
    s2 = np.zeros(c.size)
    if req_p is not None:
        s2 += np.mean(np.sum(jac[:, 3:6, :] ** 2, axis=1), axis=0) / req_p**2
    if req_r is not None:
        s2 += np.mean(np.sum(jac[:, 0:3, :] ** 2, axis=1), axis=0) / req_r**2
    with np.errstate(divide="ignore"):
        shape = np.where(s2 > 0, (1.0 / (c * np.where(s2 > 0, s2, 1.0))) ** (1.0 / 3.0), np.inf)
    return np.where(np.isfinite(shape), shape, caps * 1e6)


def _golden_section(score: Callable[[float], tuple[float, float, F64]], lo: float, hi: float,
                    rounds: int = 8) -> list[tuple[float, float, F64]]:
    """Golden-section search for the largest first entry of ``score`` on [lo, hi]; returns the
    two final candidates."""
    gr = (np.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - gr * (hi - lo), lo + gr * (hi - lo)
    f1, f2 = score(x1), score(x2)
    for _ in range(rounds):
        if f1[0] >= f2[0]:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - gr * (hi - lo)
            f1 = score(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + gr * (hi - lo)
            f2 = score(x2)
    return [f1, f2]


def allocate_tolerances(
    model: Manipulator,
    q: ArrayLike,
    *,
    rng: np.random.Generator,
    max_delta_p: float | None = 0.1,
    max_angle_rad: float | None = None,
    percentile: float = 99.0,
    distribution: str = "uniform",
    angle_scale_mm: float = 100.0,
    max_length: float = 1.0,
    max_tilt_rad: float = 0.01,
    fixed: Mapping[str, float] | None = None,
    n_search: int = 4000,
    n_verify: int = 20000,
    margin: float = 0.01,
    refine: bool = True,
    progress: bool = False,
    executor: Executor | Any | None = None,
) -> Allocation:
    """Loosest tolerances (reciprocal cost model, see the module docstring) meeting a
    percentile requirement along the trajectory, verified by a fresh nonlinear Monte Carlo.

    Args:
        q: nominal joint trajectory, shape (T, n).
        max_delta_p: requirement on max_t delta_p (length unit) at ``percentile``, or None.
        max_angle_rad: requirement on max_t theta_eps (rad) at ``percentile``, or None.
        percentile: e.g. 99 for "99 % of robots".
        angle_scale_mm: length-equivalent of 1 rad in the cost (default 100 mm).
        max_length, max_tilt_rad: caps on any allocated tolerance.
        fixed: {name or pattern: tolerance} kept as given (e.g. {"b1.*": 0}).
        n_search, n_verify: robots used by the bisection and by the verification.
        margin: the search aims at (1 - margin) times the requirement, to absorb the
            sampling noise of the verification.
        refine: also tune the split between length and angle tolerances (one factor on all
            body components, golden-section search in [1/4, 4] on the nonlinear percentile):
            the RSS shape is optimal within each kind only to first order.
        executor: where the verification Monte Carlo runs (see
            :func:`~zrp.manufacturing.population.monte_carlo`; each round takes a master seed
            from ``rng`` and every chunk draws its robots from it where it runs, so only the
            seed travels and the result does not depend on the executor).
    """
    req_p, req_r, pct = _requirement(model, max_delta_p, max_angle_rad, percentile)
    angle_scale_mm, n_search, n_verify = _check_search(distribution, angle_scale_mm, margin,
                                                       n_search, n_verify)
    space = parameter_space(model)
    arrays = trajectory_arrays(model, q)
    jac = parameter_jacobian(model, arrays[0])
    is_ang = np.array(space.units) == "rad"
    c = np.where(is_ang, angle_scale_mm, 1.0)
    caps = np.where(is_ang, nonnegative(max_tilt_rad, "max_tilt_rad", "rad"),
                    nonnegative(max_length, "max_length", model.length_unit))
    free, fixed_vals = _fixed_parameters(model, space, fixed)

    def tolerances(alpha: float, shape: F64) -> Tolerances:
        return Tolerances(np.where(free, np.minimum(alpha * shape, caps), fixed_vals),
                          space.names, space.units)

    shape = _rss_shape(jac, c, caps, req_p, req_r)
    z = draw_parameters(Tolerances(np.ones(space.size), space.names, space.units), n_search,
                        distribution, rng)
    target_p = None if req_p is None else req_p * (1 - margin)
    target_r = None if req_r is None else req_r * (1 - margin)

    def scale_to(shape: F64, rel_tol: float = 1e-4) -> float:
        return _scale_to_requirement(model, arrays, shape, caps, fixed_vals, free, z, pct,
                                     target_p, target_r, False, rel_tol=rel_tol)

    alpha = scale_to(shape)
    if refine and is_ang.any() and (~is_ang).any():
        def score(log_g: float) -> tuple[float, float, F64]:
            sh = shape * np.where(is_ang, 1.0, np.exp(log_g))
            a = scale_to(sh, rel_tol=1e-3)
            return tolerances(a, sh).looseness(angle_scale_mm), a, sh

        best = (tolerances(alpha, shape).looseness(angle_scale_mm), alpha, shape)
        for cand in _golden_section(score, np.log(0.25), np.log(4.0)):
            if cand[0] > best[0]:
                best = cand
        _, alpha, shape = best
    equal_shape = 1.0 / c
    base = tolerances(scale_to(equal_shape), equal_shape)

    rounds = 0
    while True:
        rounds += 1
        tol = tolerances(alpha, shape)
        # a master seed from rng: each chunk draws its own robots where it runs, so only the
        # seed travels (shipping 1e7 robots' draws would be 4.3 GB) and any executor gives the
        # same robots
        ver = monte_carlo(model, arrays[0], tol, n_verify, seed=int(rng.integers(2**63 - 1)),
                          distribution=distribution, progress=progress, executor=executor)
        dp, ang = ver.percentile(pct)
        r = max(dp / req_p if req_p else 0.0, ang / req_r if req_r else 0.0)
        if r <= 1.0 or rounds >= 6:
            break
        alpha *= 0.99 / r
    wc_p, wc_r = worst_case_bound(jac, tol.values)
    var_factor = 1.0 / 3.0 if distribution == "uniform" else 1.0 / 9.0
    contrib = contributions(jac, tol.values, space.names, space.units,
                            variance_factor=var_factor)
    return Allocation(
        tolerances=tol, baseline=base, looseness_mm=tol.looseness(angle_scale_mm),
        baseline_looseness_mm=base.looseness(angle_scale_mm),
        requirement={"max_delta_p": req_p, "max_angle_rad": req_r, "percentile": pct},
        verification=ver, verified=bool(r <= 1.0),
        ci_delta_p=percentile_ci(ver.max_delta_p, pct), angle_scale_mm=angle_scale_mm,
        contribution=contrib, worst_case_p=float(wc_p.max()),
        worst_case_angle_rad=float(wc_r.max()), scale_rounds=rounds)
