"""The physical domain and the manufacturing tolerance of every effect parameter: one table
for the diagnosis (a fitted value outside its domain is never accepted) and for whatever
writes a calibrated model (the same test refuses it there).

=========================  ===================================  ==============================
parameter                  domain (hard: outside it, not used)  tolerance (scale of the prior)
=========================  ===================================  ==============================
``q{k}.offset``            abs <= 0.2 rad (prismatic: 20 mm)    2 mrad (prismatic: 1 mm)
``q{k}.scale``             abs <= 0.02                          1e-3
``q{k}.sin{h}/cos{h}``     each abs <= 5 mrad; amplitude too    0.5 mrad
``q{k}.backlash``          0 <= b <= 20 mrad                    1 mrad
``q{k}.compliance``        c >= 0 (also ``_payload``)           (Jacobian scale, below)
``u{k}.t1/t2``             abs <= ``max_tilt_rad`` (5 mrad)     2 mrad
``b{k}.x/y/z``             abs <= 20 mm                         1 mm
``kappa``                  abs <= 1e-4 1/degC                   2.3e-5 1/degC (aluminium)
=========================  ===================================  ==============================

Why these: a gear train's transmission error (cyclic error) is tens to hundreds of urad on an
industrial arm, a few mrad only on worn or plastic gears; backlash is a play, never negative, and
a harmonic or cycloidal drive keeps it below a few mrad; a joint does not deflect against its
load; a machined joint axis is square to its seat to a fraction of a mrad, so a tilt of more
than a few mrad is a wrong model (a different kinematic convention, a missing joint) rather
than a calibration; the widen option is ``max_tilt_rad``. Registration parameters (base frame,
tool points) and the lumped-mass compliance weights ``q{k}.w_{p}`` (a basis for an unknown
mass distribution, whose sign is not physical) have no domain.

The tolerances scale the parameters of the well-posed identification
(:mod:`zrp.gap.fit.wellposed`): one unit of scaled parameter is one typical manufacturing or
assembly error, so a direction whose singular value is below the noise is one that the data
pin less well than the tolerance already does (eq. W2 there).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from zrp.errors import InputError
from zrp.units import metres_per_unit

__all__ = ["DEFAULT_MAX_TILT_RAD", "Domain", "domain_violations", "parameter_domain",
           "tolerance"]

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


@dataclass(frozen=True)
class Domain:
    """Where a parameter's value is physical: lo <= value <= hi (in the parameter's unit).

    Attributes:
        lo, hi: bounds (-inf / inf when open).
        why: the physical reason, in words.
    """

    lo: float
    hi: float
    why: str

    def __post_init__(self) -> None:
        if not self.lo <= self.hi:
            raise InputError(f"Domain: lo {self.lo!r} must be <= hi {self.hi!r}")

    def contains(self, value: float) -> bool:
        return bool(self.lo <= value <= self.hi)

    def describe(self, unit: str) -> str:
        lo = "" if math.isinf(self.lo) else f"{self.lo:g} <= "
        hi = "" if math.isinf(self.hi) else f" <= {self.hi:g}"
        return f"{lo}value{hi} {unit}".strip()


def _length_scale(unit: str) -> float | None:
    """Length units per metre for a length unit (None when ``unit`` is not a length)."""
    try:
        return 1.0 / metres_per_unit(unit, "unit")
    except InputError:
        return None


def _symmetric(bound: float, why: str) -> Domain:
    return Domain(-bound, bound, why)


def parameter_domain(name: str, effect: str, unit: str, *,
                     max_tilt_rad: float = DEFAULT_MAX_TILT_RAD) -> Domain | None:
    """The physical domain of one parameter (see the module table), or None when it has none.

    Args:
        name: the parameter (``q2.backlash``, ``u3.t1``, ``b4.x``...).
        effect: its effect (:data:`zrp.gap.EFFECTS`).
        unit: its unit (``rad``, ``mm``, ``rad/(N m)``...): lengths are converted.
        max_tilt_rad: the largest axis tilt accepted (widen for a part known to be tilted).
    """
    per_m = _length_scale(unit)
    if effect == "backlash":
        if per_m is not None:  # a prismatic joint's play, in a length unit
            return Domain(0.0, MAX_PLAY_M * per_m, "a play is never negative and a drive "
                          "keeps it below 1 mm")
        return Domain(0.0, 0.02, "a play is never negative and a gear train keeps it below "
                      "20 mrad")
    if effect == "joint_compliance" and name.endswith((".compliance", ".compliance_payload")):
        return Domain(0.0, math.inf, "a joint deflects with its load, not against it")
    if effect == "cyclic_error":
        if per_m is not None:
            return _symmetric(MAX_PLAY_M * per_m, "a screw's or rack's cyclic error is below "
                              "1 mm")
        return _symmetric(MAX_CYCLIC_RAD, "a gear train's cyclic transmission error is a few "
                          "mrad at most")
    if effect == "axis_misalignment":
        return _symmetric(max_tilt_rad, "a machined joint axis is square to its seat within a "
                          "few mrad")
    if effect == "link_length" and per_m is not None:
        return _symmetric(MAX_LINK_M * per_m, "a machined link is within millimetres of its "
                          "drawing")
    if effect == "joint_offset":
        return _symmetric(MAX_LINK_M * per_m if per_m is not None else MAX_OFFSET_RAD,
                          "an encoder zero error larger than this is a setup error")
    if effect == "encoder_scale":
        return _symmetric(0.02, "a gear ratio is known to better than 2 %")
    if effect == "thermal_expansion":
        return _symmetric(1e-4, "metals expand by 1e-5 to 3e-5 per degC")
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


def domain_violations(names: Sequence[str], effects: Sequence[str], units: Sequence[str],
                      values: Sequence[float] | np.ndarray, *,
                      max_tilt_rad: float = DEFAULT_MAX_TILT_RAD) -> list[tuple[int, str]]:
    """The parameters whose values leave their domains: (index, reason in words) each. A
    cyclic error's amplitude sqrt(sin^2 + cos^2) per joint and harmonic is checked too (both
    of its parameters are named)."""
    out: list[tuple[int, str]] = []
    pairs: dict[str, list[int]] = {}
    for i, (n, e, u) in enumerate(zip(names, effects, units, strict=True)):
        v = float(values[i])
        d = parameter_domain(n, e, u, max_tilt_rad=max_tilt_rad)
        if d is not None and not d.contains(v):
            out.append((i, f"{n} = {v:.3g} {u} outside {d.describe(u)}: {d.why}"))
        if e == "cyclic_error" and _length_scale(u) is None:
            pairs.setdefault(n.replace(".sin", ".h").replace(".cos", ".h"), []).append(i)
    flagged = {i for i, _ in out}
    for key, idx in pairs.items():
        amp = math.hypot(*(float(values[i]) for i in idx))
        if amp > MAX_CYCLIC_RAD and not flagged.intersection(idx):
            out += [(i, f"{key.replace('.h', ' harmonic ')} amplitude {amp:.3g} rad above "
                     f"{MAX_CYCLIC_RAD:g} rad: a gear train's cyclic transmission error is a "
                     "few mrad at most") for i in idx]
    return out
