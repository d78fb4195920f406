"""The physical domain of each identified parameter: one table for the search and the writers.

A value outside its domain is not a physical effect of a serial arm, whatever the data say:
a play (backlash) is never negative, a joint does not deflect against its load (compliance
>= 0), a gear train's cyclic transmission error is small, a machined axis is tilted by a few
mrad at most. The diagnosis's search keeps its candidates inside these domains and the
calibration writers (:mod:`zrp.calibration.validation`) refuse a file that would carry a value
outside them, with an error naming the parameter, its value and its domain.

=====================  ==================  ====================  =========================
domain (key)           parameters          bounds                unit
=====================  ==================  ====================  =========================
``backlash``           ``q{k}.backlash``   0 <= b <= 0.02        rad
``compliance``         ``q{k}.compliance``  0 <= c <= 0.01       rad/(N m)
                       ``.compliance_payload``
``cyclic_amplitude``   ``q{k}.sin{h}``,    sqrt(s^2 + c^2)       rad
                       ``q{k}.cos{h}``     <= 0.01
``encoder_scale``      ``q{k}.scale``      abs <= 0.05           1
``axis_tilt``          ``u{k}.t1``,        sqrt(t1^2 + t2^2)     rad
                       ``u{k}.t2``         <= 0.005
``thermal_expansion``  ``kappa``           abs <= 1e-4           1/degC
=====================  ==================  ====================  =========================

An upper bound holds in the table's unit only: a parameter in another unit (a prismatic
joint's play in mm, ``compliance_payload`` in rad/kg) keeps the lower bound alone. The upper
bounds are generous for an industrial arm (``zrp.gap.fit.uncertainty`` flags
smaller values as atypical); ``widen`` (a mapping key -> upper bound) raises one for an arm
that is known to need it (e.g. a hobby arm's axes). Lumped-mass compliance terms (``w_{p}``,
``w_load``) are products of unknown masses and compliances without a sign of their own and
have no domain here.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass

from zrp.errors import InputError

__all__ = ["DOMAINS", "GROUPED", "Domain", "ImplausibleValueError", "domain_key",
           "parameter_bounds", "violation"]


class ImplausibleValueError(InputError):
    """An identified value lies outside its physical domain (names parameter, value, domain)."""


@dataclass(frozen=True)
class Domain:
    """A physical domain lower <= value <= upper (of a parameter, or of the norm of a group:
    a cyclic harmonic's amplitude, an axis's total tilt); ``why`` says what it means."""

    key: str
    lower: float
    upper: float
    unit: str
    why: str

    def text(self, upper: float | None = None) -> str:
        hi = self.upper if upper is None else upper
        lo = "" if self.lower == -math.inf else f"{self.lower:g} <= "
        up = "" if hi == math.inf else f" <= {hi:g}"
        return f"{lo}value{up} {self.unit} ({self.why})"


DOMAINS: dict[str, Domain] = {d.key: d for d in (
    Domain("backlash", 0.0, 0.02, "rad", "a play is never negative"),
    Domain("compliance", 0.0, 0.01, "rad/(N m)", "a joint does not deflect against its load"),
    Domain("cyclic_amplitude", 0.0, 0.01, "rad",
           "amplitude sqrt(sin^2 + cos^2) of one harmonic: a gear train's transmission error"),
    Domain("encoder_scale", -0.05, 0.05, "1", "an encoder scale error of a few per cent"),
    Domain("axis_tilt", 0.0, 0.005, "rad",
           "total tilt sqrt(t1^2 + t2^2) of a machined axis from its nominal"),
    Domain("thermal_expansion", -1e-4, 1e-4, "1/degC",
           "expansion of metals and composites (steel 1.2e-5, aluminium 2.3e-5)"),
)}

_CYCLIC = re.compile(r"(sin|cos)\d+$")


def domain_key(name: str, effect: str) -> str | None:
    """The :data:`DOMAINS` key of parameter ``name`` of ``effect``, or None (no domain)."""
    what = name.split(".", 1)[-1]
    if effect == "backlash":
        return "backlash"
    if effect == "joint_compliance" and what in ("compliance", "compliance_payload"):
        return "compliance"
    if effect == "cyclic_error" and _CYCLIC.match(what):
        return "cyclic_amplitude"
    if effect == "encoder_scale":
        return "encoder_scale"
    if effect == "axis_misalignment":
        return "axis_tilt"
    if effect == "thermal_expansion":
        return "thermal_expansion"
    return None


#: domains bounding the norm of a group of parameters (each member is bounded alike).
GROUPED = ("cyclic_amplitude", "axis_tilt")


def _bounds(d: Domain, unit: str, widen: Mapping[str, float] | None) -> tuple[float, float]:
    """The domain's (lower, upper), widened when asked (a symmetric domain on both sides).
    The upper bound holds in the domain's unit only: a parameter in another unit (a prismatic
    joint's play in a length unit, ``compliance_payload`` in rad/kg) keeps the lower bound."""
    hi = d.upper
    if unit not in (d.unit, ""):
        hi = math.inf
    elif widen and d.key in widen:
        w = float(widen[d.key])
        if not w >= d.upper:
            raise InputError(f"widen[{d.key!r}]: {w} is below the domain's bound {d.upper:g}; "
                             "a domain can only be widened")
        hi = w
    return (-hi if d.lower == -d.upper else d.lower), hi


def parameter_bounds(name: str, effect: str, unit: str = "rad",
                     widen: Mapping[str, float] | None = None) -> tuple[float, float]:
    """Box bounds (lower, upper) of one parameter (a member of a :data:`GROUPED` domain is
    bounded by the group's bound on either side; the group itself is checked by
    :func:`violation` on its norm); (-inf, inf) without a domain."""
    key = domain_key(name, effect)
    if key is None:
        return -math.inf, math.inf
    lo, hi = _bounds(DOMAINS[key], unit, widen)
    return (-hi, hi) if key in GROUPED else (lo, hi)


def violation(key: str, name: str, value: float, unit: str = "rad",
              widen: Mapping[str, float] | None = None) -> str | None:
    """Why ``value`` of parameter ``name`` is outside domain ``key``, or None (for a
    :data:`GROUPED` domain pass the group's norm and name)."""
    d = DOMAINS[key]
    lo, hi = _bounds(d, unit, widen)
    if not (math.isfinite(value) and lo <= value <= hi):
        return (f"{name} = {value:.6g} {unit} is outside its physical domain "
                f"{Domain(key, lo, hi, d.unit, d.why).text()}")
    return None
