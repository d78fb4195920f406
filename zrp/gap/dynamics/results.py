"""The dynamic gap's typed results: a fitted parameter, a found effect, the samples for the
plots and the diagnosis (:class:`DynamicDiagnosis`); the report is a function of them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.physical import InertialFit
from zrp.gap.dynamics.resulting import BodyChange
from zrp.gap.dynamics.select import Step

__all__ = ["Baseline", "DynamicDiagnosis", "FoundEffect", "Param", "Samples"]


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
    small: bool = False  # in the model, but lowers the withheld error by too little to name

    @property
    def label(self) -> str:
        where = "arm" if self.joint is None else f"joint {self.joint + 1}"
        return f"{self.name} ({where}{', ' + self.detail if self.detail else ''})"


@dataclass(frozen=True, kw_only=True)
class Baseline:
    """The standard identification (:mod:`zrp.gap.dynamics.baseline`) on the diagnosis's samples.

    Attributes:
        keys: its effects (keys of :class:`~zrp.gap.dynamics.effect.Effect`).
        effects: the fitted values of its joint and motor terms (no intervals: a score).
        phi_change: the change of each moving body's phi (eq. R1) by its link combinations
            (unconstrained: may be no physical body; never written to a model).
        chi2: the withheld chi2 (eq. S1; 1 is the noise floor).
        rms_withheld: per joint RMS of measured minus baseline torques, each segment
            predicted by the fit on the others, N m (n,).
    """

    keys: tuple[str, ...]
    effects: list[FoundEffect] = field(default_factory=list)
    phi_change: dict[int, F64] = field(default_factory=dict)
    chi2: float = float("nan")
    rms_withheld: F64 = field(default_factory=lambda: np.zeros(0))

    @property
    def description(self) -> str:
        parts = ["Coulomb (0 at standstill) and viscous friction, rotor inertia and a torque "
                 "offset on every joint"]
        if any(k.startswith("motor_") for k in self.keys):
            parts.append("friction and rotor inertia of the coupled motors")
        if "inertial" in self.keys:
            parts.append("the link inertias' identifiable combinations (least squares, "
                         "unconstrained)")
        return "IDIM-LS: " + "; ".join(parts)


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
        baseline: the standard identification on the same samples and withheld segments
            (:mod:`zrp.gap.dynamics.baseline`), or None.
        window_s: the derivative filter's window used (chosen from the data).
        motors: each coupled motor of the log's transmission (0-based) and its joint-scale
            direction g_k (:meth:`~zrp.gap.dynamics.transmission.Transmission.coupled_motors`).
        data_problems: findings far outside any physical arm and their likely cause in the
            data (:mod:`zrp.gap.dynamics.plausible`); when any, no effect is reported.
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
    baseline: Baseline | None = None
    window_s: float = 0.1
    motors: dict[int, tuple[float, ...]] = field(default_factory=dict)
    data_problems: list[str] = field(default_factory=list)

    @property
    def found(self) -> list[FoundEffect]:
        """The findings: the effects that clearly lower the withheld error (the others are
        in the model but small)."""
        return [e for e in self.effects if not e.small]

    @property
    def measured(self) -> np.ndarray:
        """Per joint, whether its torque is data (the others were excluded from the fit)."""
        return np.array([k not in self.unmeasured for k in range(len(self.joints))])

    def effect(self, name: str, joint: int | None = None) -> FoundEffect | None:
        for e in self.effects:
            if e.name == name and e.joint == joint:
                return e
        return None
