"""The field's standard identification, fitted in the same run as the reference baseline.

What an expert fits first on any arm (inverse dynamic identification model by least squares,
IDIM-LS; Gautier & Khalil): on every measured joint Coulomb friction (a sign that is 0 at
standstill: tanh(w / V_EPS), V_EPS = 0.01 rad/s), viscous friction, rotor inertia (armature)
and a torque offset; the friction and rotor inertia of each coupled motor of a declared
transmission; the link inertial parameters' identifiable (base) combinations, physically
consistent where the log pins them (:mod:`zrp.gap.dynamics.physical`). Fitted on the same
decimated, filtered samples with the same per-joint noise weights as the diagnosis, and
scored on the same withheld time segments (and on a second log by
:func:`zrp.gap.dynamics.validation.validate`).

The diagnosis names the effects that explain the gap; this is the bar it must clear: its
final model is never worse on the withheld segments than the baseline (eq. B0, applied in
:mod:`zrp.gap.dynamics.diagnosis`; :class:`~zrp.gap.dynamics.results.Baseline` holds the
baseline's figures).
"""

from __future__ import annotations

from zrp.gap.dynamics.effect import Effect

__all__ = ["STANDARD", "standard_effects"]

#: The standard joint terms (per joint) and motor terms (per coupled motor).
STANDARD = ("coulomb", "viscous", "armature", "offset", "motor_coulomb", "motor_viscous",
            "motor_armature")


def standard_effects(effects: list[Effect]) -> list[Effect]:
    """The standard identification's candidates among ``effects`` (the plain sign for
    Coulomb friction; the link combinations when they are candidates)."""
    return [e for e in effects if (e.name in STANDARD and not e.detail.startswith("v_c="))
            or e.name == "inertial"]
