"""Plausibility as a constraint: a fitted model keeps only parameters inside their physical
domains (:mod:`zrp.gap.model.domains`).

A parameter whose value leaves its domain (both of a cyclic error's pair when their amplitude
does) is taken out of the model, which puts it back at its nominal value 0 (inside every
domain: no play, no deflection, no tilt), and the rest is refitted; repeated until every
value is inside. This is the active-set answer to a bound-constrained least-squares problem
whose bounds are met at the nominal (Lawson & Hanson 1974, ch. 23: a variable at its bound
leaves the free set), without ever clamping a value silently: every parameter taken out is
reported with the reason.

The lumped compliance weights of a joint have a domain on their sum only: when the fit wants
them to sum below 0, they are held at sum 0 (the boundary of that domain, the weights otherwise
free, :mod:`zrp.gap.fit.sumzero`) rather than taken out, and that is reported in words too
(``q3 lumped weights held at sum 0 (their free fit summed to -2.1e-06 rad/mm): ...``). A joint
with a single weight has it taken out (sum 0 is then the nominal). A joint once held stays
held in the refits of the same loop, as a parameter taken out stays out.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.sumzero import fit_sum_zero, summed_groups
from zrp.gap.model.context import REGISTRATION, Context, ParamSpec
from zrp.gap.model.domains import DOMAINS, domain_violations

__all__ = ["HELD_AT_SUM_0", "held_reason", "n_registration", "outside_domains", "sorted_out",
           "within_domains"]

#: the words that name a joint's lumped weights held at sum 0 in a reason.
HELD_AT_SUM_0 = "lumped weights held at sum 0"


def n_registration(specs: Sequence[ParamSpec]) -> int:
    """How many registration parameters lead ``specs`` (they come first)."""
    n = 0
    while n < len(specs) and specs[n].effect in REGISTRATION:
        n += 1
    return n


def outside_domains(ctx: Context, result: FitResult, first: int = 0) -> list[tuple[int, str]]:
    """(index, reason) of the parameters of ``result`` from index ``first`` on whose values
    leave their domains."""
    specs = result.specs[first:]
    found = domain_violations([s.name for s in specs], [s.effect for s in specs],
                              [s.unit for s in specs], result.theta[first:],
                              max_tilt_rad=ctx.max_tilt_rad)
    return [(first + i, why) for i, why in found]


def within_domains(ctx: Context, result: FitResult, first: int, fitting: NDArray[np.int64],
                   rb0: F64) -> tuple[FitResult, tuple[str, ...]]:
    """``result`` without the parameters (from index ``first`` on) whose values leave their
    domains, and with the lumped weights of a joint whose sum leaves it held at sum 0,
    refitted until none does (module docstring).

    Returns:
        the fit (``result`` itself when nothing left a domain) and the reasons of the
        parameters taken out or held, in words.
    """
    reasons: list[str] = []
    held: set[str] = set()
    while True:
        bad = outside_domains(ctx, result, first)
        if not bad:
            return result, tuple(dict.fromkeys(reasons))
        out, to_hold, why = sorted_out(result.specs, result.theta, bad, first)
        reasons += why
        held |= to_hold
        keep: Sequence[int] = [i for i in range(len(result.specs)) if i not in out]
        specs = [result.specs[i] for i in keep]
        theta0 = result.theta[list(keep)]
        result = fit_sum_zero(ctx, specs, held, fitting, theta0, rb0)


def sorted_out(specs: Sequence[ParamSpec], theta: F64, bad: Sequence[tuple[int, str]],
               first: int) -> tuple[set[int], set[str], list[str]]:
    """The violations ``bad`` ((index, reason), indices into ``specs``) sorted: the indices
    to take out, the joints whose lumped weights to hold at sum 0 (those with two or more
    weights; a single weight is taken out), and the reasons in words."""
    sums = summed_groups(specs, first)
    in_sum = {i: j for j, idx in sums.items() for i in idx}
    to_hold = {in_sum[i] for i, _ in bad if i in in_sum and len(sums[in_sum[i]]) > 1}
    out = {i for i, _ in bad if in_sum.get(i) not in to_hold}
    reasons = [why for i, why in bad if i in out]
    reasons += [held_reason(specs, theta, j, sums[j]) for j in sorted(to_hold)]
    return out, to_hold, reasons


def held_reason(specs: Sequence[ParamSpec], theta: F64, joint: str, idx: Sequence[int]) -> str:
    """Why the lumped weights ``idx`` of ``joint`` (values ``theta``) are held at sum 0."""
    total = float(np.sum(theta[list(idx)]))
    names = ", ".join(specs[i].name for i in idx)
    return (f"{joint} {HELD_AT_SUM_0} (their free fit summed to {total:.3g} "
            f"{specs[idx[0]].unit}: {names}), not taken out: "
            f"{DOMAINS['lumped_compliance'].why}")
