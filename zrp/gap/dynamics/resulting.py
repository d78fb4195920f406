"""The model's bodies after the chosen effects of its masses, and their physical domain.

The physical domain holds the *resulting* body, not the change (a hand the arm does not carry
is a negative change of the tool body; what must stay physical is the link without it). For
each moving body b (eq. R1 layout, phi in the body's frame):

* ``inertial``: phi_b from the physically consistent link fit (:mod:`.physical`);
* ``link_mass``: phi_b plus a point mass dm at d from the link's centre (eq. B2);
* ``absent_part`` (tool body): phi_tool - s phi_part (eq. B1);
* ``payload`` (tool body): phi_tool plus a point mass m at the tool point p + d (d = (m d) / m,
  eq. E2); a negative mass takes one away.

A body is physical when its pseudo-inertia is positive semi-definite (eq. R5, to rounding) and
its mass >= 0; a massless body with no first or second moments is physical (nothing there).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.bodies import link_centre
from zrp.gap.dynamics.inertia import add_point_mass, pseudo_inertia

__all__ = ["BodyChange", "ChangedArm", "link_changes", "physical_body", "resulting_bodies"]


@dataclass(frozen=True)
class BodyChange:
    """A body changed by the effects: its name, the model's phi, the resulting phi, which
    effects changed it (effect keys) and, once measured along the log, the RMS torque the
    change adds on each joint."""

    body: int
    name: str
    phi0: F64
    phi: F64
    effects: tuple[str, ...]
    torque_rms: F64 | None = None  # the RMS torque the change adds on each joint (n,)

    @property
    def mass_change(self) -> float:
        return float(self.phi[0] - self.phi0[0])

    @property
    def centre_shift_m(self) -> float:
        """How far the centre of mass moves, m (0 for a body without mass)."""
        m0, m1 = float(self.phi0[0]), float(self.phi[0])
        if m0 <= 0.0 or m1 <= 0.0:
            return 0.0
        return float(np.linalg.norm(self.phi[1:4] / m1 - self.phi0[1:4] / m0))

    @property
    def physical(self) -> bool:
        return physical_body(self.phi)


def physical_body(phi: F64) -> bool:
    """Whether phi (eq. R1) is a physical body (module docstring)."""
    if not np.all(np.isfinite(phi)):
        return False
    j = pseudo_inertia(phi)
    scale = max(float(np.abs(j).max()), 1e-12)
    return phi[0] >= -1e-9 * scale and float(np.linalg.eigvalsh(j).min()) >= -1e-9 * scale


def _point_mass(phi: F64, values: Mapping[str, float], p: F64) -> F64:
    """phi plus a point mass m at p + d (eq. E2 with m d given)."""
    m = values["mass"]
    if m == 0.0:
        return phi
    d = np.array([values["m*dx"], values["m*dy"], values["m*dz"]]) / m
    return add_point_mass(phi, m, np.asarray(p, dtype=float) + d)


def _apply(arm: Arm, name: str, detail: str, values: Mapping[str, float], phi: F64,
           ) -> F64:
    if name == "link_mass":
        b = _target(arm, name, detail)
        return _point_mass(phi, values, link_centre(arm, b))
    if name == "absent_part":
        part = next(a for a in arm.attachments if a.name == detail)
        return phi - values["share"] * part.phi
    return _point_mass(phi, values, arm.tool_point)


def _target(arm: Arm, name: str, detail: str) -> int | None:
    if name in ("absent_part", "payload"):
        return arm.tool_body
    if name == "link_mass":
        return next((b for b in arm.moving_bodies() if arm.body_name(b) == detail), None)
    return None


def resulting_bodies(arm: Arm, effects: list[tuple[str, str, str, Mapping[str, float]]],
                     inertial_phi: Mapping[int, F64] | None = None) -> dict[int, BodyChange]:
    """Every body the effects change: ``effects`` as (key, name, detail, parameter values),
    ``inertial_phi`` the physical link fit's bodies (their starting point when given)."""
    out: dict[int, BodyChange] = {}
    for b, phi in (inertial_phi or {}).items():
        phi0 = arm.body_params(b)
        if not np.allclose(phi, phi0, rtol=1e-12, atol=1e-15):
            out[b] = BodyChange(b, arm.body_name(b), phi0, np.asarray(phi, float), ("inertial",))
    for key, name, detail, values in effects:
        b = _target(arm, name, detail)
        if b is None:
            continue
        prev = out.get(b)
        phi0 = arm.body_params(b) if prev is None else prev.phi0
        start = (arm.body_params(b) if inertial_phi is None or b not in inertial_phi
                 else np.asarray(inertial_phi[b], float)) if prev is None else prev.phi
        out[b] = BodyChange(b, arm.body_name(b), phi0, _apply(arm, name, detail, values, start),
                            (*(prev.effects if prev else ()), key))
    return out


class ChangedArm:
    """An arm whose model bodies are replaced by ``phi`` (body -> eq. R1 parameters), all
    else the arm's own: the model the link inertias are fitted against once a named part or
    link of it has been changed (the physical fit then holds the resulting body)."""

    def __init__(self, arm: Arm, phi: Mapping[int, F64]) -> None:
        self._arm = arm
        self._phi = {b: np.asarray(v, dtype=float) for b, v in phi.items()}

    def __getattr__(self, name: str) -> object:
        return getattr(self._arm, name)

    def body_params(self, b: int) -> F64:
        return self._phi[b].copy() if b in self._phi else self._arm.body_params(b)


def link_changes(arm: Arm, inertial_phi: Mapping[int, F64],
                 named: Mapping[int, BodyChange]) -> dict[int, BodyChange]:
    """The bodies after the link inertias fitted on top of named changes (``named``: the
    bodies a part or link effect changed first), each against the arm's own model."""
    out: dict[int, BodyChange] = {}
    for b, phi in inertial_phi.items():
        phi0 = arm.body_params(b)
        if np.allclose(phi, phi0, rtol=1e-12, atol=1e-15) and b not in named:
            continue
        keys = (*(named[b].effects if b in named else ()), "inertial")
        out[b] = BodyChange(b, arm.body_name(b), phi0, np.asarray(phi, float), keys)
    return out
