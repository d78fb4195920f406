"""The physical domain and the manufacturing tolerance of every effect parameter: one table
for the diagnosis (a fitted value outside its domain is never accepted) and for whatever writes
a calibrated model (:mod:`zrp.calibration.validation` refuses it there, naming the parameter,
its value and its domain).

=====================  ============================  ====================================
domain (key)           parameters                    domain (hard: outside it, not used)
=====================  ============================  ====================================
``joint_offset``       ``q{k}.offset``               abs <= 0.2 rad (prismatic: 20 mm)
``encoder_scale``      ``q{k}.scale``                abs <= 0.02
``cyclic_amplitude``   ``q{k}.sin{h}``, ``.cos{h}``  each and sqrt(s^2 + c^2) <= 5 mrad
                                                     (prismatic: 1 mm)
``backlash``           ``q{k}.backlash``             0 <= b <= 20 mrad (prismatic: 1 mm)
``compliance``         ``q{k}.compliance``,          0 <= c <= 0.01 rad/(N m)
                       ``.compliance_payload``,      (in rad/kg, and the lumped weights
                       ``.w_{p}``, ``.w_load``       in rad/length, rad/(length kg):
                                                     c >= 0 only)
``axis_tilt``          ``u{k}.t1``, ``u{k}.t2``      each and sqrt(t1^2 + t2^2) <=
                                                     ``max_tilt_rad`` (5 mrad)
``link_length``        ``b{k}.x/y/z``                abs <= 20 mm
``thermal_expansion``  ``kappa``                     abs <= 1e-4 1/degC
=====================  ============================  ====================================

Tolerances (the scale of the prior, :func:`tolerance`): offset 2 mrad (prismatic 1 mm), scale
1e-3, cyclic 0.5 mrad, backlash 1 mrad, tilt 2 mrad, link 1 mm, kappa 2.3e-5 1/degC
(aluminium); compliance and the registration are scaled by their Jacobian columns.

Why these: a gear train's transmission error (cyclic error) is tens to hundreds of urad on an
industrial arm, a few mrad only on worn or plastic gears; backlash is a play, never negative, and
a harmonic or cycloidal drive keeps it below a few mrad; a joint does not deflect against its
load; a machined joint axis is square to its seat to a fraction of a mrad, so a tilt of more
than a few mrad is a wrong model (a different kinematic convention, a missing joint) rather than
a calibration. An arm known to need more passes ``widen`` (key -> a larger upper bound;
``max_tilt_rad`` of the diagnosis is the same thing for ``axis_tilt``): a domain can only be
widened. Registration parameters (base frame, tool points) have no domain.

The lumped-mass compliance weights ``q{k}.w_{p}`` are products c_k m_p g of joint k's
compliance and a mass lumped at point p on the gravity moment arm of
:meth:`zrp.gap.model.context.Context.moment_arms` (the same sign as the MJCF gravity torque of
``q{k}.compliance``). The points are the ones the chain offers (joint origins, the flange), so
the arm's real masses are represented by weights that sum to the mass they stand for, and one
weight alone may be negative: a centre of mass behind a joint or a counterweight lumped on the
points ahead of it. What physics fixes is their sum per joint, c_k times the mass joint k
carries (domain ``lumped_compliance``: >= 0, a joint deflects with its load in total); a
negative sum leaves the domain as a negative ``q{k}.compliance`` does (the fits then hold
that joint's weights at sum 0, the domain's bound, :mod:`zrp.gap.fit.sumzero`; the writers
refuse a negative sum, allowing :data:`SUM_RTOL` for the rounding of a sum held at 0).
``q{k}.w_load`` is a known mass (per kg of payload at the tool) and has the ``compliance``
domain itself (>= 0).

The tolerances scale the parameters of the well-posed identification
(:mod:`zrp.gap.fit.wellposed`): one unit of scaled parameter is one typical manufacturing or
assembly error, so a direction whose singular value is below the noise is one that the data pin
less well than the tolerance already does (eq. W2 there).

This module imports no NumPy: the command line's help lists the domain keys.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from zrp.errors import InputError

__all__ = ["DEFAULT_MAX_TILT_RAD", "DOMAINS", "GROUPED", "SUMMED", "SUM_RTOL", "Domain",
           "ImplausibleValueError",
           "domain_key", "domain_violations", "parameter_bounds", "parameter_domain",
           "sum_inside", "summed_members", "tolerance", "violation"]

#: Largest axis tilt accepted by default (rad): a few mrad of a machined part.
DEFAULT_MAX_TILT_RAD = 5e-3
#: Largest cyclic-error component or amplitude (rad) a gear train can produce.
MAX_CYCLIC_RAD = 5e-3
#: Largest link (body-vector) correction, metres.
MAX_LINK_M = 0.02
#: Largest play or cyclic error of a prismatic joint, metres.
MAX_PLAY_M = 1e-3
#: Largest encoder zero error (rad; prismatic joints: MAX_LINK_M).
MAX_OFFSET_RAD = 0.2


class ImplausibleValueError(InputError):
    """An identified value lies outside its physical domain (names parameter, value, domain)."""


@dataclass(frozen=True)
class Domain:
    """A physical domain lower <= value <= upper in ``unit`` (of a parameter, or of the norm
    of a :data:`GROUPED` group: a cyclic harmonic's amplitude, an axis's total tilt).

    Attributes:
        key: the domain's name (:data:`DOMAINS`).
        lower, upper: bounds (-inf / inf when open).
        unit: the unit of the bounds.
        why: the physical reason, in words.
        length_upper_m: the upper bound (metres) when the parameter is a length instead
            (a prismatic joint's play, offset or cyclic error); None: no upper bound then.
    """

    key: str
    lower: float
    upper: float
    unit: str
    why: str
    length_upper_m: float | None = None

    def __post_init__(self) -> None:
        if not self.lower <= self.upper:
            raise InputError(f"Domain {self.key}: lower {self.lower!r} must be <= upper "
                             f"{self.upper!r}")

    @property
    def lo(self) -> float:
        return self.lower

    @property
    def hi(self) -> float:
        return self.upper

    @property
    def symmetric(self) -> bool:
        return self.lower == -self.upper

    def contains(self, value: float) -> bool:
        return bool(math.isfinite(value) and self.lower <= value <= self.upper)

    def describe(self, unit: str | None = None) -> str:
        lo = "" if math.isinf(self.lower) else f"{self.lower:g} <= "
        hi = "" if math.isinf(self.upper) else f" <= {self.upper:g}"
        return f"{lo}value{hi} {self.unit if unit is None else unit}".strip()

    def text(self, upper: float | None = None) -> str:
        hi = self.upper if upper is None else upper
        lo = "" if self.lower == -math.inf else f"{self.lower:g} <= "
        up = "" if hi == math.inf else f" <= {hi:g}"
        return f"{lo}value{up} {self.unit} ({self.why})"


DOMAINS: dict[str, Domain] = {d.key: d for d in (
    Domain("joint_offset", -MAX_OFFSET_RAD, MAX_OFFSET_RAD, "rad",
           "an encoder zero error larger than this is a setup error", MAX_LINK_M),
    Domain("encoder_scale", -0.02, 0.02, "1", "a gear ratio is known to better than 2 %"),
    Domain("cyclic_amplitude", 0.0, MAX_CYCLIC_RAD, "rad",
           "amplitude sqrt(sin^2 + cos^2) of one harmonic: a gear train's cyclic transmission "
           "error is a few mrad at most", MAX_PLAY_M),
    Domain("backlash", 0.0, 0.02, "rad",
           "a play is never negative and a gear train keeps it below 20 mrad", MAX_PLAY_M),
    Domain("compliance", 0.0, 0.01, "rad/(N m)",
           "a joint deflects with its load, not against it"),
    Domain("lumped_compliance", 0.0, math.inf, "rad/length",
           "the lumped weights of one joint sum to its compliance times the mass it carries: "
           "a joint deflects with its load in total (one weight alone may be negative, a mass "
           "behind the joint)"),
    Domain("axis_tilt", 0.0, DEFAULT_MAX_TILT_RAD, "rad",
           "total tilt sqrt(t1^2 + t2^2) of a machined axis from its nominal: square to its "
           "seat within a few mrad"),
    Domain("link_length", -MAX_LINK_M, MAX_LINK_M, "m",
           "a machined link is within millimetres of its drawing", MAX_LINK_M),
    Domain("thermal_expansion", -1e-4, 1e-4, "1/degC",
           "expansion of metals and composites (steel 1.2e-5, aluminium 2.3e-5)"),
)}

#: domains bounding the norm of a group of parameters (each member is bounded alike).
GROUPED = ("cyclic_amplitude", "axis_tilt")
#: domains bounding the sum of a joint's parameters (a member alone has no bound).
SUMMED = ("lumped_compliance",)
#: a sum held at its bound 0 is computed with one rounding (:mod:`zrp.gap.fit.sumzero`):
#: a sum down to -SUM_RTOL sum |w| is on the bound (4 eps: four
#: times the bound eps sum |w| of that rounding).
SUM_RTOL = 4.0 * 2.0 ** -52

_CYCLIC = re.compile(r"(sin|cos)\d+$")
_BY_EFFECT = {"joint_offset": "joint_offset", "encoder_scale": "encoder_scale",
              "backlash": "backlash", "axis_misalignment": "axis_tilt",
              "thermal_expansion": "thermal_expansion"}


def _length_scale(unit: str) -> float | None:
    """Length units per metre for a length unit (None when ``unit`` is not a length)."""
    from zrp.units import metres_per_unit  # NumPy: only when a domain is evaluated

    try:
        return 1.0 / metres_per_unit(unit, "unit")
    except InputError:
        return None


def domain_key(name: str, effect: str) -> str | None:
    """The :data:`DOMAINS` key of parameter ``name`` of ``effect``, or None (no domain)."""
    what = name.split(".", 1)[-1]
    if effect in _BY_EFFECT:
        return _BY_EFFECT[effect]
    if effect == "joint_compliance" and what in ("compliance", "compliance_payload", "w_load"):
        return "compliance"
    if effect == "joint_compliance" and what.startswith("w_"):
        return "lumped_compliance"
    if effect == "cyclic_error" and _CYCLIC.match(what):
        return "cyclic_amplitude"
    if effect == "link_length" and name.startswith("b"):
        return "link_length"
    return None


def _bounds(d: Domain, unit: str, widen: Mapping[str, float] | None) -> tuple[float, float]:
    """The domain's (lower, upper) for a parameter in ``unit``, widened when asked (a
    symmetric domain on both sides). In another length unit the upper bound is converted
    (``length_upper_m``); in any other unit (``compliance_payload`` in rad/kg) only the lower
    bound holds."""
    hi = d.upper
    if unit not in (d.unit, ""):
        per_m = _length_scale(unit) if d.length_upper_m is not None else None
        hi = math.inf if per_m is None else d.length_upper_m * per_m
    elif widen and d.key in widen:
        w = float(widen[d.key])
        if not w >= d.upper:
            raise InputError(f"widen[{d.key!r}]: {w} is below the domain's bound {d.upper:g}; "
                             "a domain can only be widened")
        hi = w
    return (-hi if d.symmetric else d.lower), hi


def parameter_bounds(name: str, effect: str, unit: str = "rad",
                     widen: Mapping[str, float] | None = None) -> tuple[float, float]:
    """Box bounds (lower, upper) of one parameter (a member of a :data:`GROUPED` domain is
    bounded by the group's bound on either side; the group itself is checked by
    :func:`violation` on its norm); (-inf, inf) without a domain."""
    key = domain_key(name, effect)
    if key is None or key in SUMMED:
        return -math.inf, math.inf
    lo, hi = _bounds(DOMAINS[key], unit, widen)
    return (-hi, hi) if key in GROUPED else (lo, hi)


def parameter_domain(name: str, effect: str, unit: str, *,
                     max_tilt_rad: float = DEFAULT_MAX_TILT_RAD) -> Domain | None:
    """The physical domain of one parameter (its box: a :data:`GROUPED` member is bounded on
    both sides by the group's bound), or None when it has none.

    Args:
        name: the parameter (``q2.backlash``, ``u3.t1``, ``b4.x``...).
        effect: its effect (:data:`zrp.gap.EFFECTS`).
        unit: its unit (``rad``, ``mm``, ``rad/(N m)``...): lengths are converted.
        max_tilt_rad: the largest axis tilt accepted (widen for a part known to be tilted).
    """
    key = domain_key(name, effect)
    if key is None or key in SUMMED:  # the sum of the joint's weights has the domain
        return None
    d = DOMAINS[key]
    if key == "axis_tilt":
        return Domain(key, -max_tilt_rad, max_tilt_rad, unit or d.unit, d.why)
    lo, hi = parameter_bounds(name, effect, unit)
    return Domain(key, lo, hi, unit or d.unit, d.why)


def violation(key: str, name: str, value: float, unit: str = "rad",
              widen: Mapping[str, float] | None = None) -> str | None:
    """Why ``value`` of parameter ``name`` is outside domain ``key``, or None (for a
    :data:`GROUPED` domain pass the group's norm and name)."""
    d = DOMAINS[key]
    lo, hi = _bounds(d, unit, widen)
    if not (math.isfinite(value) and lo <= value <= hi):
        shown = unit if lo == 0.0 and hi == math.inf else d.unit  # no bound to convert
        return (f"{name} = {value:.6g} {unit} is outside its physical domain "
                f"{Domain(key, lo, hi, shown, d.why).text()}")
    return None


def tolerance(name: str, effect: str, unit: str) -> float | None:
    """A typical manufacturing or assembly error of the parameter (the scale of the prior of
    :mod:`zrp.gap.fit.wellposed`), or None when it has none in absolute terms (compliance, the
    registration: scaled by their Jacobian columns there)."""
    per_m = _length_scale(unit)
    fixed = {"joint_offset": 1e-3 * per_m if per_m is not None else 2e-3,
             "encoder_scale": 1e-3,
             "cyclic_error": 5e-5 * per_m if per_m is not None else 5e-4,
             "backlash": 1e-4 * per_m if per_m is not None else 1e-3,
             "axis_misalignment": 2e-3, "thermal_expansion": 2.3e-5,
             "link_length": 1e-3 * per_m if per_m is not None else None}
    return fixed.get(effect)


def _group(name: str, key: str) -> str:
    """The group a member of a :data:`GROUPED` domain belongs to (``q3 harmonic 1``, ``u2``)."""
    if key == "axis_tilt":
        return name.split(".", 1)[0]
    return re.sub(r"\.(sin|cos)(\d+)$", r" harmonic \2", name)


def domain_violations(names: Sequence[str], effects: Sequence[str], units: Sequence[str],
                      values: Sequence[float], *,
                      max_tilt_rad: float = DEFAULT_MAX_TILT_RAD) -> list[tuple[int, str]]:
    """The parameters whose values leave their domains: (index, reason in words) each. The
    norm of each :data:`GROUPED` group (a cyclic harmonic's amplitude sqrt(sin^2 + cos^2), an
    axis's total tilt sqrt(t1^2 + t2^2)) is checked too, naming all of its members."""
    out: list[tuple[int, str]] = []
    groups: dict[tuple[str, str], list[int]] = {}
    for i, (n, e, u) in enumerate(zip(names, effects, units, strict=True)):
        v = float(values[i])
        d = parameter_domain(n, e, u, max_tilt_rad=max_tilt_rad)
        if d is None:
            continue
        if not d.contains(v):
            out.append((i, f"{n} = {v:.3g} {u} outside {d.describe(u)}: {d.why}"))
        if d.key in GROUPED:
            groups.setdefault((d.key, _group(n, d.key)), []).append(i)
    flagged = {i for i, _ in out}
    out += _sum_violations(names, effects, units, values)
    for (key, group), idx in groups.items():
        bound = parameter_domain(names[idx[0]], effects[idx[0]], units[idx[0]],
                                 max_tilt_rad=max_tilt_rad)
        assert bound is not None
        norm = math.hypot(*(float(values[i]) for i in idx))
        if norm > bound.upper and not flagged.intersection(idx):
            out += [(i, f"{group} {'tilt' if key == 'axis_tilt' else 'amplitude'} {norm:.3g} "
                     f"{units[i]} above {bound.upper:g} {units[i]}: {DOMAINS[key].why}")
                    for i in idx]
    return out


def sum_inside(values: Sequence[float]) -> bool:
    """Whether lumped weights ``values`` of one joint sum inside ``lumped_compliance``: the
    fsum >= -:data:`SUM_RTOL` times the sum of their magnitudes (a sum held at 0 rounds to
    either side of it; every value finite)."""
    v = [float(x) for x in values]
    if not all(math.isfinite(x) for x in v):
        return False
    return math.fsum(v) >= DOMAINS["lumped_compliance"].lower - SUM_RTOL * math.fsum(
        abs(x) for x in v)


def summed_members(names: Sequence[str], effects: Sequence[str],
                   first: int = 0) -> dict[str, list[int]]:
    """Per joint (``q3``), the indices (from ``first`` on) of its parameters in a
    :data:`SUMMED` domain (its lumped weights)."""
    out: dict[str, list[int]] = {}
    for i in range(first, len(names)):
        if domain_key(names[i], effects[i]) in SUMMED:
            out.setdefault(names[i].split(".", 1)[0], []).append(i)
    return out


def _sum_violations(names: Sequence[str], effects: Sequence[str], units: Sequence[str],
                    values: Sequence[float]) -> list[tuple[int, str]]:
    """Every member of a joint's :data:`SUMMED` group whose sum leaves its domain."""
    out: list[tuple[int, str]] = []
    for joint, idx in summed_members(names, effects).items():
        total = math.fsum(float(values[i]) for i in idx)
        if not sum_inside([float(values[i]) for i in idx]):
            out += [(i, f"{names[i]} = {float(values[i]):.3g} {units[i]} (the lumped weights "
                     f"of {joint} sum to {total:.3g}) outside 0 <= sum: a joint deflects with "
                     "its load in total") for i in idx]
    return out
