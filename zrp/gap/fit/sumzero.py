"""Lumped compliance weights held at sum 0: the least-squares fit on the boundary of their
domain.

The weights ``q{k}.w_{p}`` of joint k have a domain on their sum only (``lumped_compliance``
of :mod:`zrp.gap.model.domains`: sum_p w_p >= 0). When the free fit wants a negative sum, the
answer of least squares subject to that inequality (Kuhn-Tucker: the constraint active) is
the fit on its boundary, sum_p w_p = 0 with the weights otherwise free, not every weight at 0
(taking them all out, as for a parameter with a domain of its own, is a stricter model and
fits worse). The equality is met by eliminating the last weight L of the joint,

    w_L = -sum_{p != L} w_p,    q' = q + sum_{p != L} w_p (B_p - B_L)                  (S1)

(the weights enter the joint values through their bases B_p, :mod:`zrp.gap.model.effects`),
so the fit estimates the other weights with the bases B_p - B_L (the Jacobian columns
J_p - J_L), and the result maps back by theta = T phi (T: identity on the free parameters, a
row of -1 for w_L). The covariance follows, C = T C_phi T^T: the eliminated weight's
variance is 1^T C_others 1 and its covariances with the others make the sum's variance
exactly 0 (a fit with constraints carries T in ``FitResult.tied``; its statistics count the
free parameters). w_L is computed as -fsum of the others, so the sum is exact up to one
rounding of that fsum (|sum| <= eps sum_p |w_p|); the domain check allows
:data:`zrp.gap.model.domains.SUM_RTOL` sum_p |w_p| below 0 for that reason.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Sequence

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.leastsq import FitResult, fit
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.domains import summed_members
from zrp.gap.model.problem import Problem

__all__ = ["SumZero", "expanded", "fit_sum_zero", "held_joints", "mapped_cov", "summed_groups"]


def summed_groups(specs: Sequence[ParamSpec], first: int = 0) -> dict[str, list[int]]:
    """Per joint (``q3``), the indices (from ``first`` on) of its lumped weights."""
    return summed_members([s.name for s in specs], [s.effect for s in specs], first)


@dataclasses.dataclass(frozen=True)
class SumZero:
    """The reparametrisation (S1) of ``specs`` with the weights of ``joints`` summing to 0.

    Attributes:
        specs: the parameters (p).
        free: the free coordinates' specs (f = p - len(eliminated)): the eliminated weights
            left out, the other weights of their joints with the bases B_p - B_L.
        tied: T, shape (p, f): theta = T phi.
        eliminated: per held joint, (index of w_L, indices of its other weights).
    """

    specs: tuple[ParamSpec, ...]
    free: tuple[ParamSpec, ...]
    tied: F64
    eliminated: tuple[tuple[int, tuple[int, ...]], ...]

    @classmethod
    def of(cls, specs: Sequence[ParamSpec], joints: Collection[str]) -> SumZero:
        """(S1) for the joints named (each with at least two weights in ``specs``)."""
        specs = tuple(specs)
        groups = summed_groups(specs)
        elim = tuple((groups[j][-1], tuple(groups[j][:-1])) for j in sorted(joints))
        gone = {last for last, _ in elim}
        diff = {o: specs[last].basis for last, others in elim for o in others}
        free_idx = [i for i in range(len(specs)) if i not in gone]
        free = tuple(dataclasses.replace(specs[i], basis=_minus(specs[i].basis, diff[i]))
                     if i in diff else specs[i] for i in free_idx)
        T = np.zeros((len(specs), len(free_idx)))
        T[free_idx, np.arange(len(free_idx))] = 1.0
        col = {i: c for c, i in enumerate(free_idx)}
        for last, others in elim:
            T[last, [col[o] for o in others]] = -1.0
        return cls(specs, free, T, elim)

    def theta(self, phi: F64) -> F64:
        """theta = T phi, each eliminated weight -fsum of its joint's others (module doc)."""
        theta = self.tied @ phi
        for last, others in self.eliminated:
            theta[last] = -math.fsum(float(theta[o]) for o in others)
        return theta

    def phi(self, theta: F64) -> F64:
        """The free coordinates of ``theta`` (the eliminated weights dropped)."""
        gone = {last for last, _ in self.eliminated}
        return np.array([v for i, v in enumerate(theta) if i not in gone], dtype=float)


def held_joints(result: FitResult) -> set[str]:
    """The joints (``q3``) whose lumped weights ``result`` holds at sum 0 (its eliminated
    weights: the rows of ``tied`` with a -1)."""
    if result.tied is None:
        return set()
    rows = np.flatnonzero(np.any(result.tied < 0, axis=1))
    return {result.specs[i].name.split(".", 1)[0] for i in rows}


def _minus(a: F64 | None, b: F64 | None) -> F64:
    assert a is not None and b is not None
    out = a - b
    out.setflags(write=False)
    return out


def fit_sum_zero(ctx: Context, specs: Sequence[ParamSpec], joints: Collection[str],
                 fitting: NDArray[np.int64], theta0: F64, rb0: F64) -> FitResult:
    """:func:`~zrp.gap.fit.leastsq.fit` of ``specs`` with the lumped weights of ``joints``
    summing to 0 (S1), mapped back to ``specs`` (:func:`expanded`); the plain fit when
    ``joints`` is empty."""
    if not joints:
        return fit(ctx, list(specs), fitting, theta0, rb0)
    sz = SumZero.of(specs, joints)
    fr = fit(ctx, list(sz.free), fitting, sz.phi(np.asarray(theta0, dtype=float)), rb0)
    return expanded(ctx, sz, fr)


def expanded(ctx: Context, sz: SumZero, fr: FitResult) -> FitResult:
    """The fit ``fr`` of the free coordinates of ``sz`` as a fit of its ``specs``: theta =
    T phi, ``cov`` = T C_phi T^T (``held_cov`` alike), the residual and Jacobian of ``specs``
    at theta, ``tied`` = T."""
    theta = sz.theta(fr.theta)
    T = sz.tied
    r, J = Problem(ctx, sz.specs, fr.poses, fr.base_rotation).residual_and_jacobian(theta)
    return FitResult(sz.specs, theta, mapped_cov(T, fr.cov), r, J, fr.base_rotation,
                     fr.poses, fr.converged, fr.held, fr.stop_reason, fr.iterations,
                     fr.probe_rotation,
                     None if fr.held_cov is None else mapped_cov(T, fr.held_cov), T)


def mapped_cov(T: F64, C: F64) -> F64:
    """T C T^T, shape (p, p), summing only the terms T actually has (0 inf is not NaN: an
    infinite variance of one free coordinate stays in the rows that depend on it)."""
    if np.all(np.isfinite(C)):
        return T @ C @ T.T
    rows = [np.flatnonzero(t) for t in T]
    out = np.empty((T.shape[0], T.shape[0]))
    for i, a in enumerate(rows):
        for j, b in enumerate(rows):
            out[i, j] = float(T[i, a] @ C[np.ix_(a, b)] @ T[j, b])
    return out
