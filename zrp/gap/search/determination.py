"""What the data determine, per parameter of the final model: one interval story for every
table and file (issue 33).

A parameter is

* **held** when it belongs to a combination the data cannot pin (:mod:`zrp.gap.fit.wellposed`):
  it stayed at its nominal value, and its interval says nothing the tolerance did not;
* **undetermined** when its 95 % interval (or its effect's simultaneous one) is wider than its
  physical domain
  (:mod:`zrp.gap.model.domains`), or, for a parameter without a domain (the registration's base
  frame and tool points, lumped compliance weights), when moving it across half its interval
  moves the measured points by more than the whole withheld RMS after registration (eq. D1):
  its uncertainty alone is then as large as the error being calibrated, and the parameters it
  trades against
  (correlation >= :data:`PARTNER_RHO`) name the direction it belongs to;
* **determined** otherwise.

Eq. D1, for a parameter i with 95 % half-width h_i and Jacobian column J_i (the residual's
derivative, 3 rows per measured point)::

    h_i * sqrt(3 * mean(J_i^2)) > RMS_withheld(after registration)

(the 3-D displacement RMS over the measured points that h_i causes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.uncertainty import Correlations, correlations
from zrp.gap.model.domains import parameter_domain
from zrp.gap.search.steps import ParameterEstimate, parameter_estimates

__all__ = ["PARTNER_RHO", "Determination", "determinations", "fit_determinations"]

#: |correlation| from which a parameter is named as one an undetermined one trades against.
PARTNER_RHO = 0.9
#: partners named at most.
MAX_PARTNERS = 3


@dataclass(frozen=True)
class Determination:
    """What the data say about one parameter.

    Attributes:
        name: the parameter.
        status: "determined", "held" or "undetermined".
        direction: for a held one the held combination (its label); for an undetermined one
            the parameters it trades against with their correlations ("" when none is
            strong) or why it is undetermined.
    """

    name: str
    status: str
    direction: str = ""

    @property
    def determined(self) -> bool:
        return self.status == "determined"

    def describe(self) -> str:
        """"determined", "in a combination held at nominal (...)" or "undetermined
        (...)"."""
        if self.determined:
            return "determined"
        head = "in a combination held at nominal" if self.status == "held" else "undetermined"
        return f"{head} ({self.direction})" if self.direction else head

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "status": self.status, "direction": self.direction}


def _partners(name: str, corr: Correlations | None) -> str:
    if corr is None or name not in corr.names:
        return ""
    i = corr.names.index(name)
    row = [(abs(r), r, n) for n, r in zip(corr.names, corr.matrix[i], strict=True)
           if n != name and math.isfinite(r) and abs(r) >= PARTNER_RHO]
    row.sort(key=lambda t: -t[0])
    return ", ".join(f"{n} {r:+.2f}" for _, r, n in row[:MAX_PARTNERS])


def _wider_than_domain(p: ParameterEstimate, max_tilt_rad: float) -> str | None:
    """Why the interval is wider than the domain, None when it is not (or has no domain)."""
    dom = parameter_domain(p.name, p.effect, p.unit, max_tilt_rad=max_tilt_rad)
    if dom is None or not (math.isfinite(dom.lo) and math.isfinite(dom.hi)):
        return None
    for what, (lo, hi) in (("95 % interval", p.ci95),
                           ("interval for the whole effect", p.ci95_effect or p.ci95)):
        if not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo > dom.hi - dom.lo:
            return f"{what} wider than its domain {dom.describe()}"
    return None


def _moves_more_than(p: ParameterEstimate, jac: Mapping[str, float], gap: float,
                     unit: str) -> str | None:
    """Eq. D1 for a parameter without a domain; None when it is determined."""
    col = jac.get(p.name)
    lo, hi = p.ci95
    if col is None:
        return None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "no finite interval"
    moved = 0.5 * (hi - lo) * col
    if moved > gap:
        return f"its interval moves the points by {moved:.3g} {unit}"
    return None


def determinations(fit: FitResult, estimates: Sequence[ParameterEstimate], *,
                   gap: float, unit: str, max_tilt_rad: float,
                   correlations: Correlations | None = None) -> dict[str, Determination]:
    """Name -> :class:`Determination` for ``estimates`` (the registration and the final
    model's parameters of ``fit``).

    Args:
        fit: the final fit (its held combinations, Jacobian and specs).
        estimates: the parameters with their (robust) 95 % intervals.
        gap: the withheld RMS after registration (length unit), the yardstick of eq. D1.
        unit: the length unit.
        max_tilt_rad: the axis-tilt domain of the diagnosis.
        correlations: of the final model's parameters (names the partners).
    """
    held = {n: h.label for h in fit.held for n in h.parameters}
    n_res = fit.residual.size
    cols = np.sqrt(3.0 * np.mean(fit.jac[:n_res] ** 2, axis=0)) if n_res else np.zeros(0)
    jac = {s.name: float(c) for s, c in zip(fit.specs, cols, strict=False)}
    out = {}
    for p in estimates:
        if p.name in held:
            out[p.name] = Determination(p.name, "held", held[p.name])
            continue
        why = _wider_than_domain(p, max_tilt_rad)
        if why is None and parameter_domain(p.name, p.effect, p.unit) is None:
            why = _moves_more_than(p, jac, gap, unit)
        if why is None:
            out[p.name] = Determination(p.name, "determined")
            continue
        partners = _partners(p.name, correlations)
        out[p.name] = Determination(p.name, "undetermined",
                                    why + (f"; trades against {partners}" if partners else ""))
    return out


def fit_determinations(fit: FitResult, *, gap: float, unit: str, max_tilt_rad: float
                       ) -> dict[str, Determination]:
    """:func:`determinations` of every parameter of a fit from its own (normal-theory)
    intervals and correlations (another estimate than the diagnosis's final model, e.g. a
    full-pose refit)."""
    est = parameter_estimates(fit, 0, simultaneous=True)
    return determinations(fit, est, gap=gap, unit=unit, max_tilt_rad=max_tilt_rad,
                          correlations=correlations(tuple(s.name for s in fit.specs),
                                                    fit.cov))
