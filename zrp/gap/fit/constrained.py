"""Plausibility as a constraint: a fitted model keeps only parameters inside their physical
domains (:mod:`zrp.gap.model.domains`).

A parameter whose value leaves its domain (both of a cyclic error's pair when their amplitude
does) is taken out of the model, which puts it back at its nominal value 0 (inside every
domain: no play, no deflection, no tilt), and the rest is refitted; repeated until every
value is inside. This is the active-set answer to a bound-constrained least-squares problem
whose bounds are met at the nominal (Lawson & Hanson 1974, ch. 23: a variable at its bound
leaves the free set), without ever clamping a value silently: every parameter taken out is
reported with the reason.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.leastsq import FitResult, fit
from zrp.gap.model.context import REGISTRATION, Context, ParamSpec
from zrp.gap.model.domains import domain_violations

__all__ = ["n_registration", "outside_domains", "within_domains"]


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
    domains, refitted until none does (module docstring).

    Returns:
        the fit (``result`` itself when nothing left a domain) and the reasons of the
        parameters taken out, in words.
    """
    reasons: list[str] = []
    while True:
        bad = outside_domains(ctx, result, first)
        if not bad:
            return result, tuple(dict.fromkeys(reasons))
        out = {i for i, _ in bad}
        reasons += [why for _, why in bad]
        keep: Sequence[int] = [i for i in range(len(result.specs)) if i not in out]
        result = fit(ctx, [result.specs[i] for i in keep], fitting, result.theta[list(keep)],
                     rb0)
