"""What these data can identify, and whether the data or the robot's structure is to blame.

A parameter that the data cannot tell apart from others is reported, never absorbed silently.
To say whether *these poses* or *the robot's structure* make it so, the same check runs on a
rich reference set of random poses (:class:`ReferencePoses`, built once per diagnosis from its
own seeded stream): what the reference set cannot identify either is structural.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.analysis.checks import GapWarning
from zrp.gap.data.measurements import Measurements
from zrp.gap.fit.aliasing import ALIAS_TOL, Aliased
from zrp.gap.fit.leastsq import FitResult, check_identifiable, orthonormal_basis
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem
from zrp.jsonio import dict_from_dataclass

__all__ = [
    "GEOMETRIC",
    "EffectIdentifiability",
    "ReferencePoses",
    "geometric_overlap",
    "registration_identifiable",
    "sequential_alias",
    "survey",
]

#: the geometric effects (offsets, scales, links, tilts).
GEOMETRIC = ("joint_offset", "encoder_scale", "link_length", "axis_misalignment")
#: poses in the reference set.
N_REFERENCE = 200
#: revolute joints of the reference set turn over +-this (rad); prismatic ones move over
#: 0 .. PRISMATIC_SHARE x the reach.
REVOLUTE_RANGE = 2.5
PRISMATIC_SHARE = 0.3


@dataclass(frozen=True)
class EffectIdentifiability:
    """Which parameters of one effect these data cannot identify on top of the registration.

    Attributes:
        not_identifiable: parameters dropped (aliased with others).
        weak: parameters kept but only weakly identifiable.
        limited_by_data: names of the dropped ones that a rich pose set would identify.
    """

    not_identifiable: tuple[Aliased, ...]
    weak: tuple[Aliased, ...]
    limited_by_data: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


class ReferencePoses:
    """A rich random pose set for the same model, tool points and frame (seeded, its own
    stream drawn from ``rng`` on construction; the context is built on first use).

    The temperatures (when the data have a ``temp`` column) are drawn over 15-30 deg C.
    """

    def __init__(self, ctx: Context, rng: np.random.Generator, n_poses: int = N_REFERENCE
                 ) -> None:
        self.ctx = ctx
        self.n_poses = n_poses
        self._rng = np.random.default_rng(rng.integers(2**32))

    @cached_property
    def context(self) -> Context:
        ctx, P = self.ctx, self.n_poses
        meas = ctx.meas
        M, n = len(meas.point_labels), ctx.n
        lim = np.where(ctx.model.prismatic[:, None], [[0.0, PRISMATIC_SHARE * ctx.model.reach]],
                       [[-REVOLUTE_RANGE, REVOLUTE_RANGE]])
        qref = self._rng.uniform(lim[:, 0], lim[:, 1], (P, n))
        temp = None if meas.temp is None else np.repeat(self._rng.uniform(15, 30, P), M)
        ref = Measurements.from_arrays(np.repeat(np.arange(P), M), np.repeat(qref, M, 0),
                                       np.zeros((P * M, 3)),
                                       point=np.tile(list(meas.point_labels), P),
                                       frame=meas.frame, temp=temp, source="reference poses")
        return Context(ctx.model, ref, None, ctx.gravity_dir, ctx.harmonics)

    @property
    def poses(self) -> NDArray[np.int64]:
        return np.arange(self.n_poses)

    def fit_like(self, result: FitResult) -> FitResult:
        """``result``'s parameters placed on the reference poses (a zero residual), to check
        candidates on top of it."""
        R = 3 * self.n_poses * len(self.ctx.meas.point_labels)
        return FitResult(result.specs, result.theta, result.cov, np.zeros(R),
                         np.zeros((R, len(result.specs))), result.base_rotation, self.poses,
                         True)


def sequential_alias(J: F64, names: Sequence[str], fixed: int) -> list[tuple[int, str]]:
    """Columns (from index ``fixed`` on) that are combinations of the columns before them:
    (index, partners) pairs (Gram-Schmidt on normalised columns, tolerance ALIAS_TOL)."""
    norms = np.linalg.norm(J, axis=0)
    A = J / np.where(norms > 0, norms, 1.0)
    Q = orthonormal_basis(A[:, :fixed])
    accepted = list(range(fixed))
    out: list[tuple[int, str]] = []
    for i in range(fixed, J.shape[1]):
        c = A[:, i]
        r = c - Q @ (Q.T @ c)
        r = r - Q @ (Q.T @ r)
        f = float(np.linalg.norm(r))
        if norms[i] == 0 or f < ALIAS_TOL:
            corr = np.abs(A[:, accepted].T @ c) if accepted else np.zeros(0)
            partners = [names[accepted[o]] for o in np.argsort(-corr)[:3]
                        if corr[o] >= 0.5 * corr.max()] if corr.size else []
            out.append((i, "/".join(partners)))
            continue
        accepted.append(i)
        Q = np.column_stack([Q, r / f])
    return out


def registration_identifiable(ctx: Context, specs: list[ParamSpec], poses: NDArray[np.int64],
                              theta0: F64, rb0: F64, reference: ReferencePoses
                              ) -> tuple[list[ParamSpec], F64]:
    """Drop registration parameters that no pose set could identify (e.g. the tool offsets
    along the common axis of a SCARA, which trade against the base translation), with a
    warning; raise when these data cannot identify one that richer poses would."""
    names = [s.name for s in specs]
    fixed = 6 if ctx.meas.frame == "instrument" else 0
    _, J = Problem(ctx, specs, poses, rb0).residual_and_jacobian(theta0)
    # the base frame itself must be identifiable
    base_bad = sequential_alias(J[:, :fixed], names[:fixed], 0) if fixed else []
    data_bad = base_bad + sequential_alias(J, names, fixed)
    if not data_bad:
        return specs, theta0
    _, Jr = Problem(reference.context, specs, reference.poses, rb0).residual_and_jacobian(theta0)
    _refuse_data_limited(ctx, names, data_bad, {i for i, _ in sequential_alias(Jr, names, fixed)},
                         fixed)
    drop = {i for i, _ in data_bad}
    warnings.warn(f"registration: {', '.join(names[i] for i in sorted(drop))} cannot be told "
                  "apart from the other registration parameters for this robot (structural); "
                  "fixed at 0 and carried by " + ", ".join(sorted({p for _, p in data_bad})),
                  GapWarning, stacklevel=2)
    keep = [i for i in range(len(specs)) if i not in drop]
    return [specs[i] for i in keep], theta0[keep]


def _refuse_data_limited(ctx: Context, names: list[str], data_bad: list[tuple[int, str]],
                         structural: set[int], fixed: int) -> None:
    """Raise when a registration parameter these data cannot identify is not structurally
    aliased (richer poses would identify it), or is one of the ``fixed`` base-frame ones."""
    limited = [(i, p) for i, p in data_bad if i not in structural or i < fixed]
    if limited:
        what = ", ".join(f"{names[i]} ~ {p or 'nothing'}" for i, p in limited)
        raise InputError(
            f"{ctx.meas.source}: the registration is not identifiable from these poses "
            f"({what}); the joints must move enough to rotate the tool in several directions")


def _warn_still_joints(ctx: Context, poses: NDArray[np.int64]) -> None:
    """Warn about joints that (almost) do not move over ``poses``."""
    for k in range(ctx.n):
        rng_k = float(np.ptp(ctx.q[poses, k]))
        small = 1e-3 if not ctx.model.prismatic[k] else 1e-3 * ctx.model.characteristic_length
        if rng_k < small:
            warnings.warn(f"{ctx.meas.source}: joint {k + 1} does not move in the fitting poses "
                          f"(range {rng_k:.3g}); its offset, scale and other parameters cannot "
                          "be told apart", GapWarning, stacklevel=2)


def survey(ctx: Context, reg: FitResult,
           specs_of: Mapping[str, tuple[list[ParamSpec], str | None]],
           reference: ReferencePoses) -> dict[str, EffectIdentifiability]:
    """Which parameters of each effect these data cannot identify on top of the registration,
    and which of those the reference poses would identify (so the data, not the model
    structure, are to blame: a warning names them)."""
    _warn_still_joints(ctx, reg.poses)
    ref_ctx = reference.context
    reports: dict[str, list[Aliased]] = {}
    union: list[ParamSpec] = []
    ref_union: list[ParamSpec] = []
    for eff, (specs, _) in specs_of.items():
        if not specs:
            continue
        _, reports[eff] = check_identifiable(ctx, reg, specs)
        union += specs
        ref_union += effect_parameters(ref_ctx, eff)[0]
    # all effects together, on the data and on the rich reference poses
    _, rep = check_identifiable(ctx, reg, union)
    _, ref_rep = check_identifiable(ref_ctx, reference.fit_like(reg), ref_union)
    limited = _data_limited(rep, {a.name for a in ref_rep if a.dropped}, reports)
    return {eff: EffectIdentifiability(tuple(a for a in rep if a.dropped),
                                       tuple(a for a in rep if not a.dropped),
                                       tuple(limited[eff]))
            for eff, rep in reports.items()}


def _data_limited(rep: list[Aliased], structural: set[str], effects: Mapping[str, object]
                  ) -> dict[str, list[str]]:
    """Per effect, the dropped parameters that are not ``structural`` (richer poses would
    identify them), with one warning per effect (attributed to the caller of :func:`survey`)."""
    limited: dict[str, list[str]] = {eff: [] for eff in effects}
    by_effect: dict[str, list[str]] = {}
    for a in rep:
        if a.dropped and a.name not in structural:
            by_effect.setdefault(a.effect, []).append(
                f"{a.name} ~ {'/'.join(a.partners) or 'nothing'}")
            limited[a.effect].append(a.name)
    for eff, items in by_effect.items():
        warnings.warn(f"rank-deficient data: {'; '.join(items)} ({eff}) cannot be identified "
                      "from these poses although richer poses would identify them; move the "
                      "joints over wider ranges", GapWarning, stacklevel=3)
    return limited


def geometric_overlap(ctx: Context, current: FitResult, correction: F64) -> float:
    """Share of a step's correction (change of the predicted positions on the fitting poses,
    shape (3R,)) that the geometric effects together (offsets, scales, links, tilts) on top of
    the current model could reproduce: 1 means the step is indistinguishable from geometry
    over these poses, 0 that it is entirely non-geometric."""
    geo: list[ParamSpec] = []
    for eff in GEOMETRIC:
        geo += effect_parameters(ctx, eff)[0]
    have = {s.name for s in current.specs}
    keep, _ = check_identifiable(ctx, current, [g for g in geo if g.name not in have])
    prob = Problem(ctx, list(current.specs) + keep, current.poses, current.base_rotation)
    _, J = prob.residual_and_jacobian(np.concatenate([current.theta, np.zeros(len(keep))]))
    jn = np.linalg.norm(J, axis=0)
    Q = orthonormal_basis(J / np.where(jn > 0, jn, 1.0))
    cc = float(correction @ correction)
    if cc <= 0:
        return 0.0
    return float(np.sum((Q.T @ correction) ** 2) / cc)
