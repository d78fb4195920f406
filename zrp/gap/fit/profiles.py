"""Profiled choices of the ``backlash`` effect: which flank of its play a joint rests on.

A joint with play lags against its approach direction unless gravity (beating the load's
Coulomb friction) holds it on the loaded flank. Which side that is, and above which gravity
torque it happens, is chosen on the fitting poses by profiling on top of the current model:

* :func:`with_gravity_side`: without MJCF inertias, the sign of the gravity torque comes from a
  lumped-mass compliance fit;
* :func:`with_backlash_switch`: per joint the switching torque (and, with MJCF torques, an
  unknown payload at the tool), with profile-likelihood weights of the plausible switches;
* :func:`switch_bands`: the range of plausible switching torques, for the report.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.leastsq import (
    FitResult,
    check_identifiable,
    fit,
    group_key,
    orthonormal_basis,
    wald_groups,
)
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem
from zrp.units import G_STANDARD, metres_per_unit

__all__ = ["PAYLOAD_GRID_KG", "switch_bands", "with_backlash_switch", "with_gravity_side"]

#: payloads at the tool profiled with MJCF torques, kg.
PAYLOAD_GRID_KG = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0)
#: a threshold (or payload) must remove this many residual variances more than the default.
CLEARLY_MORE = 25.0
#: switching-torque weights per joint: (plausible thresholds, their weights) per joint.
Weights = tuple[tuple[tuple[float, ...], tuple[float, ...]], ...]


def with_gravity_side(ctx: Context, reg: FitResult, fitting: NDArray[np.int64], rb0: F64,
                      alpha: float) -> Context:
    """Without MJCF inertias, which side of its play a gravity-loaded joint rests against is
    taken from the sign of the gravity torque of a lumped-mass compliance fit (fitting poses
    only), for the joints where that fit is significant; elsewhere equal unit masses decide."""
    specs, _ = effect_parameters(ctx, "joint_compliance")
    keep, _ = check_identifiable(ctx, reg, specs)
    side = ctx.gravity_side_torque()
    if not keep:
        return ctx
    nreg = len(reg.specs)
    fc = fit(ctx, list(reg.specs) + keep, fitting,
             np.concatenate([reg.theta, np.zeros(len(keep))]), rb0)
    pv = wald_groups(fc, nreg)
    thr = alpha / max(len(pv), 1)
    tau = np.zeros_like(side)
    sig_joint = np.zeros(ctx.n, dtype=bool)
    for i, s in enumerate(keep):
        if pv[group_key(s)] < thr:
            assert s.basis is not None
            tau += fc.theta[nreg + i] * s.basis
            sig_joint[s.joint - 1] = True
    if not sig_joint.any():
        return ctx
    return dataclasses.replace(ctx, gravity_side=np.where(sig_joint, tau, side))


@dataclass(frozen=True)
class _Gains:
    """Residual removed by one play parameter of joint k for switching torques F, with the
    columns projected off span(Q): gain(F) = (c.r)^2 / (|c|^2 - |Q^T c|^2) where the column
    c = sum over rows of G_k B_F(pose). Everything is reduced per pose first, so a candidate
    costs O(S q) instead of O(R q)."""

    M: F64  # (S, q): Q^T G_k summed per pose
    u: F64  # (S,): r . G_k summed per pose
    nv: F64  # (S,): |G_k|^2 summed per pose
    tau_k: F64  # (S,)
    d_k: F64  # (S,)

    @classmethod
    def of(cls, Q: F64, rp: F64, Gk: F64, pose: NDArray[np.int64], S: int, tau_k: F64,
           d_k: F64) -> _Gains:
        """Q: orthonormal columns (3R, q); rp: residual (3R,), orthogonal to Q; Gk: dx/dq_k
        per row (R, 3); pose: pose of each row (R,) in 0..S-1; tau_k, d_k: torque and
        approach per pose (S,)."""
        R = Gk.shape[0]
        q = Q.shape[1]
        QtG = np.einsum("rcq,rc->rq", Q.reshape(R, 3, q), Gk)
        M = np.zeros((S, q))
        np.add.at(M, pose, QtG)
        u = np.bincount(pose, weights=np.einsum("rc,rc->r", rp.reshape(R, 3), Gk), minlength=S)
        nv = np.bincount(pose, weights=np.einsum("rc,rc->r", Gk, Gk), minlength=S)
        return cls(M, u, nv, tau_k, d_k)

    def __call__(self, grid: F64) -> F64:
        B = np.where(np.abs(self.tau_k)[:, None] > grid[None, :], np.sign(self.tau_k)[:, None],
                     -self.d_k[:, None])  # (S, m)
        den = self.nv @ B**2 - np.sum((self.M.T @ B) ** 2, axis=0)
        num = (self.u @ B) ** 2
        return np.where(den > 1e-12 * max(float(self.nv.sum()), 1e-300), num / np.where(
            den > 0, den, 1.0), 0.0)


def switch_bands(dists: Weights | None, mass: float = 0.99) -> list[list[float] | None]:
    """Per joint, the range of switching torques holding ``mass`` of the profile weight
    (None for joints modelled by the approach direction only)."""
    out: list[list[float] | None] = []
    for thr, w in dists or ():
        t = np.asarray(thr, dtype=float)
        if t.size == 1 and not np.isfinite(t[0]):
            out.append(None)
            continue
        order = np.argsort(t)
        t, cw = t[order], np.cumsum(np.asarray(w, dtype=float)[order])
        lo = t[np.searchsorted(cw, (1.0 - mass) / 2)]
        hi = t[min(np.searchsorted(cw, 1.0 - (1.0 - mass) / 2), t.size - 1)]
        out.append([float(lo), float(hi)])
    return out


@dataclass(frozen=True)
class _PlayFit:
    """The linearised play fit on top of the current model (fitting poses).

    Attributes:
        r: residual (3R,); Abase: normalised Jacobian columns of the current model;
        Qbase: their orthonormal basis; G: dx/dq_k per row, shape (R, 3, n); pose: pose of
        each row; d: approach direction per pose (S, n); s2: residual variance; base: the
        current model's fit.
    """

    r: F64
    Abase: F64
    Qbase: F64
    G: F64
    pose: NDArray[np.int64]
    d: F64
    s2: float
    base: FitResult

    @property
    def S(self) -> int:
        return self.d.shape[0]

    @classmethod
    def of(cls, ctx: Context, base: FitResult, fitting: NDArray[np.int64]) -> _PlayFit:
        n = ctx.n
        unit = [ParamSpec(f"q{k + 1}.unit", "rad", "joint_offset", "dq", k + 1, 0,
                          np.eye(n)[k][None, :].repeat(len(ctx.q), 0)) for k in range(n)]
        prob = Problem(ctx, list(base.specs) + unit, fitting, base.base_rotation)
        r, J = prob.residual_and_jacobian(np.concatenate([base.theta, np.zeros(n)]))
        nb = len(base.specs)
        jn = np.linalg.norm(J[:, :nb], axis=0)
        Abase = J[:, :nb] / np.where(jn > 0, jn, 1.0)
        return cls(r, Abase, orthonormal_basis(Abase), J[:, nb:].reshape(-1, 3, n),
                   prob.row_pose, ctx.meas.approach_direction()[fitting], base.rss / base.dof,
                   base)

    def columns(self, tau: F64, k: int, grid: F64) -> F64:
        """Basis columns of joint k's play for thresholds ``grid`` (m,): shape (3R, m)."""
        B = np.where(np.abs(tau[:, k])[:, None] > grid[None, :],
                     np.sign(tau[:, k])[:, None], -self.d[:, k][:, None])  # (S, m)
        return (self.G[:, :, k][:, :, None] * B[self.pose][:, None, :]).reshape(-1, grid.size)

    def gains(self, tau: F64, grids: dict[int, F64], switch: F64, k: int) -> _Gains:
        """The gain function of joint k with the other joints' play (at ``switch``) in the
        model."""
        others = [self.columns(tau, j, switch[j:j + 1])[:, 0] for j in grids if j != k]
        A = np.column_stack([self.Abase, *[c / max(np.linalg.norm(c), 1e-300)
                                           for c in others]])
        Q = orthonormal_basis(A)
        rp = self.r - Q @ (Q.T @ self.r)
        return _Gains.of(Q, rp, self.G[:, :, k], self.pose, self.S, tau[:, k], self.d[:, k])


def _grids(pf: _PlayFit, tau: F64, max_candidates: int) -> dict[int, F64]:
    """Per joint that can show play: inf, the data's |torque| values (at most
    ``max_candidates`` quantiles) ascending, and 0."""
    grids: dict[int, F64] = {}
    for k in range(tau.shape[1]):
        a = np.abs(tau[:, k])
        approach = bool(np.any(pf.d[:, k] > 0) and np.any(pf.d[:, k] < 0))
        if not (approach or np.any(a > 0)):
            continue
        qs = np.unique(a[a > 0])
        if qs.size > max_candidates:
            qs = np.unique(np.quantile(qs, np.linspace(0.0, 1.0, max_candidates)))
        grids[k] = np.array([np.inf, *qs.tolist(), 0.0]) if qs.size else np.array([np.inf])
    return grids


def _refine(gains_of: _Gains, grid: F64, gains: F64, i: int, tau_k: F64) -> float:
    """A finite threshold grid[i] > 0 refined between its neighbouring grid values with every
    data value, then put half-way to the next larger |torque| of the data (|torque| <= the
    threshold keeps the approach side)."""
    best = float(grid[i])
    a = np.unique(np.abs(tau_k))
    lo = grid[i - 1] if i - 1 >= 1 else 0.0
    hi = grid[i + 1] if i + 1 <= grid.size - 2 else a.max()
    fine = a[(a >= lo) & (a <= hi)]
    if fine.size:
        g2 = gains_of(fine)
        j = int(np.argmax(g2))
        if g2[j] >= gains[i]:
            best = float(fine[j])
    above = a[a > best]
    return 0.5 * (best + above.min()) if above.size else best


def _sweep(pf: _PlayFit, tau: F64, grids: dict[int, F64], sweeps: int) -> F64:
    """Thresholds per joint by coordinate sweeps: for each joint in turn (the others' play
    in the model) the threshold that removes the most residual; infinity unless another
    removes clearly more."""
    switch = np.full(tau.shape[1], np.inf)
    for _ in range(sweeps):
        changed = False
        for k, grid in grids.items():
            if grid.size == 1:
                continue
            gains_of = pf.gains(tau, grids, switch, k)
            gains = gains_of(grid)
            i = int(np.argmax(gains))
            best = float(grid[i]) if gains[i] > gains[0] + CLEARLY_MORE * pf.s2 else np.inf
            if np.isfinite(best) and best > 0:
                best = _refine(gains_of, grid, gains, i, tau[:, k])
            if best != switch[k]:
                switch[k] = best
                changed = True
        if not changed:
            break
    return switch


def _removed(pf: _PlayFit, tau: F64, grids: dict[int, F64], switch: F64) -> float:
    """Residual the play of all joints at ``switch`` removes together (length unit^2)."""
    C = np.column_stack([pf.columns(tau, k, switch[k:k + 1])[:, 0] for k in grids])
    C = C - pf.Qbase @ (pf.Qbase.T @ C)
    cn = np.linalg.norm(C, axis=0)
    Qc = orthonormal_basis(C / np.where(cn > 0, cn, 1.0))
    rp = pf.r - pf.Qbase @ (pf.Qbase.T @ pf.r)
    return float(np.sum((Qc.T @ rp) ** 2))


def _weights(pf: _PlayFit, tau: F64, grids: dict[int, F64], switch: F64, total: float
             ) -> Weights:
    """How sure is each threshold? Profile-likelihood weights exp(-d(RSS) / 2 sigma^2), with
    sigma^2 from the residual left after the play is modelled."""
    s2a = max((pf.base.rss - total) / max(pf.base.dof - len(grids), 1), 1e-30)
    dists: list[tuple[tuple[float, ...], tuple[float, ...]]] = []
    for k in range(tau.shape[1]):
        if k not in grids or not np.isfinite(switch[k]):
            dists.append(((float(switch[k]),), (1.0,)))
            continue
        a = np.unique(np.abs(tau[:, k]))
        a = a[a > 0]
        cand = np.array([*a.tolist(), 0.0, float(switch[k])])
        g = pf.gains(tau, grids, switch, k)(cand)
        w = np.exp(-(g.max() - g) / (2.0 * s2a))
        keep = w > 1e-6 * w.max()
        dists.append((tuple(cand[keep].tolist()), tuple((w[keep] / w[keep].sum()).tolist())))
    return tuple(dists)


def _select(pf: _PlayFit, tau: F64, sweeps: int, max_candidates: int
            ) -> tuple[F64, float, Weights]:
    """Thresholds per joint, the residual they remove together (length unit^2) and per
    joint the plausible thresholds with their weights."""
    grids = _grids(pf, tau, max_candidates)
    switch = _sweep(pf, tau, grids, sweeps)
    if not grids:
        return switch, 0.0, ()
    total = _removed(pf, tau, grids, switch)
    return switch, total, _weights(pf, tau, grids, switch, total)


def with_backlash_switch(ctx: Context, base: FitResult, fitting: NDArray[np.int64],
                         sweeps: int = 2, max_candidates: int = 40) -> Context:
    """Per joint, the gravity torque above which a joint with play rests on the loaded flank
    instead of lagging against its approach direction (Coulomb friction of the load holds it
    below). Chosen on the fitting poses by profiling on top of the current model ``base``,
    joint by joint with the other joints' play in the model (a few coordinate sweeps): for
    thresholds at 0, the data's |torque| values (at most ``max_candidates`` quantiles) and
    infinity, the play fit that removes the most residual wins; infinity (the plain
    approach-direction model) unless another threshold removes clearly more (by 25 sigma^2).
    With MJCF torques, an unknown payload at the tool (which shifts the torques) is profiled
    too, over :data:`PAYLOAD_GRID_KG`, kept when it removes clearly more (25 sigma^2)."""
    pf = _PlayFit.of(ctx, base, fitting)
    tau0 = ctx.gravity_side_torque()[fitting]
    switch, gain, dists = _select(pf, tau0, sweeps, max_candidates)
    payload = 0.0
    if ctx.gravity_torque is not None:
        h_ee = ctx.end_effector_arms()[fitting]
        to_m = metres_per_unit(ctx.model.length_unit, "model.length_unit")
        for m in PAYLOAD_GRID_KG[1:]:
            sw_m, g_m, d_m = _select(pf, tau0 + G_STANDARD * m * h_ee * to_m, sweeps,
                                     max_candidates)
            if g_m > gain + CLEARLY_MORE * pf.s2:
                switch, gain, dists, payload = sw_m, g_m, d_m, m
    return dataclasses.replace(ctx, backlash_switch=tuple(float(v) for v in switch),
                               backlash_switch_weights=dists or None, payload_kg=payload)
