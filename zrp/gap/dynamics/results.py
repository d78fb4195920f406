"""The dynamic gap's typed results: a fitted parameter, a found effect, the samples for the
plots and the diagnosis (:class:`DynamicDiagnosis`); the report is a function of them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.physical import InertialFit
from zrp.gap.dynamics.resulting import BodyChange
from zrp.gap.dynamics.select import Step

__all__ = ["DynamicDiagnosis", "FoundEffect", "Param", "Samples"]


@dataclass(frozen=True)
class Param:
    """A fitted parameter: value, 95 % interval, unit, and whether it sits on its bound."""

    value: float
    low: float
    high: float
    unit: str
    at_bound: bool = False


@dataclass(frozen=True)
class FoundEffect:
    """A chosen effect: its key, name, joint (0-based or None), detail, parameters and the
    withheld chi2 drop it brought."""

    key: str
    name: str
    joint: int | None
    detail: str
    params: dict[str, Param]
    chi2_drop: float
    rms_nm: F64 | None = None  # the RMS torque it adds on each joint along the log (n,)

    @property
    def label(self) -> str:
        where = "arm" if self.joint is None else f"joint {self.joint + 1}"
        return f"{self.name} ({where}{', ' + self.detail if self.detail else ''})"


@dataclass(frozen=True)
class Samples:
    """The states and residuals at the fit rate, for plots: q, qd, and measured (raw) minus
    model torques before and after (withheld), each (S, n)."""

    t: F64
    q: F64
    qd: F64
    before: F64
    after: F64


@dataclass(frozen=True)
class DynamicDiagnosis:
    """The result (all torques in N m, per joint arrays of shape (n,)).

    Attributes:
        arm, joints: names.
        noise_nm: the torque noise floor sigma_k (eq. N1).
        rms_before: RMS of measured minus model torques (raw torques).
        rms_after: RMS of measured minus corrected torques, each time segment predicted by
            the fit on the others (withheld).
        steps: the forward selection (nominal first) with the withheld chi2 after each.
        effects: the chosen effects, the model's physics before the sensors' offsets and
            gains, each in order of the torque it explains (RMS over all joints, N m;
            ``steps`` has the order of choice).
        cannot_tell: what this log cannot separate, in words.
        regimes: {"before"|"after": {regime: [rms or None per joint]}}.
        inertial_fit: the physically consistent link inertia fit (None: no inertial effect
            chosen), with how far it is from the unconstrained one
            (:class:`zrp.gap.dynamics.physical.InertialFit`).
        inertial_phi: phi_b (eq. R1) of each moving body after it.
        notes: what else the user should know.
        samples: the states and residuals at the fit rate (plots).
        bodies: every body the effects of the masses change (payload, absent part, link
            mass, link inertias), with its resulting phi, all physical
            (:mod:`zrp.gap.dynamics.resulting`).
        unmeasured: joints whose torque is not data (constant, zero), excluded from the fit
            and from every overall figure, with why.
    """

    arm: str
    joints: list[str]
    noise_nm: F64
    rms_before: F64
    rms_after: F64
    steps: list[Step]
    effects: list[FoundEffect]
    cannot_tell: list[str]
    regimes: dict[str, dict[str, list[float | None]]]
    inertial_fit: InertialFit | None = None
    inertial_phi: dict[int, F64] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    samples: Samples | None = None
    bodies: dict[int, BodyChange] = field(default_factory=dict)
    unmeasured: dict[int, str] = field(default_factory=dict)

    @property
    def measured(self) -> np.ndarray:
        """Per joint, whether its torque is data (the others were excluded from the fit)."""
        return np.array([k not in self.unmeasured for k in range(len(self.joints))])

    def effect(self, name: str, joint: int | None = None) -> FoundEffect | None:
        for e in self.effects:
            if e.name == name and e.joint == joint:
                return e
        return None
