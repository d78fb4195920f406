"""The corrected model scored on another log (``--validate LOG2``): the diagnosis is fitted on
one run; its effects, with the values fitted there, predict the torques of a second run the
fit never saw (another excitation, another day). Per joint and overall RMS before (the
model) and after (the corrected model), against that log's own noise floor.

The prediction (eq. V1) along the second log's states is the model's inverse dynamics plus
the exact torque change Y_b (phi_b - phi0_b) (eq. R2) of every body the diagnosis changed
(:attr:`DynamicDiagnosis.bodies`: link inertias, a part not on the arm, a link's mass, a
payload), and each other found effect's columns (:mod:`.effects`) times its fitted values.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.diagnosis import (
    DynamicDiagnosis,
    DynamicsOptions,
    decimated_states,
    model_torques,
    torque_noise,
)
from zrp.gap.dynamics.effects import candidate_effects
from zrp.gap.dynamics.results import Baseline
from zrp.gap.dynamics.transmission import Transmission

__all__ = ["Validation", "validate"]


@dataclass(frozen=True)
class Validation:
    """The corrected model on a second log (all N m, per joint arrays (n,)).

    Attributes:
        source: the second log's name.
        noise_nm: its torque noise floor (eq. N1).
        rms_before: RMS of measured minus model torques.
        rms_after: RMS of measured minus corrected-model torques (nothing refitted).
        samples: the samples compared.
    """

    source: str
    noise_nm: F64
    rms_before: F64
    rms_after: F64
    samples: int
    measured: np.ndarray | None = None  # per joint: its torque is data (None: all)
    rms_baseline: F64 | None = None  # the standard identification's, nothing refitted

    @property
    def overall_baseline(self) -> float | None:
        return None if self.rms_baseline is None else self._overall(self.rms_baseline)

    def _overall(self, x: F64) -> float:
        m = np.ones(x.size, dtype=bool) if self.measured is None else self.measured
        return float(np.sqrt(np.mean(x[m] ** 2)))

    @property
    def overall_before(self) -> float:
        return self._overall(self.rms_before)

    @property
    def overall_after(self) -> float:
        return self._overall(self.rms_after)

    @property
    def overall_noise(self) -> float:
        return self._overall(self.noise_nm)


def _prediction(arm: Arm, diag: DynamicDiagnosis, q: F64, qd: F64, qdd: F64, tau0: F64,
                transmission: Transmission | None = None) -> F64:
    """Eq. V1: the found effects' torques along the states (S, n)."""
    keys = {e.key for e in diag.effects}
    cols = {e.key: e for e in candidate_effects(arm, q, qd, qdd, tau0, inertial=False,
                                                transmission=transmission)
            if e.key in keys}
    pred = np.zeros_like(tau0)
    # the changed bodies at their resulting inertials (eq. R2): every part, link and payload
    # effect and the link inertias at once
    in_bodies = {k for c in diag.bodies.values() for k in c.effects}
    if diag.bodies:
        bodies = sorted(diag.bodies)
        y, _ = arm.regressor(q, qd, qdd, bodies)
        pred += y @ np.concatenate([diag.bodies[b].phi - diag.bodies[b].phi0 for b in bodies])
    for f in diag.effects:
        if f.key in in_bodies:
            continue
        e = cols.get(f.key)
        if e is None:
            raise InputError(f"validate: effect {f.key} cannot be evaluated on this arm")
        pred += e.columns @ np.array([f.params[p].value for p in e.params])
    return pred


def _baseline_prediction(arm: Arm, base: Baseline, q: F64, qd: F64, qdd: F64, tau0: F64,
                         transmission: Transmission | None) -> F64:
    """The standard identification's torques along the states (its link combinations as the
    change of every body's phi, its joint and motor terms by their columns)."""
    pred = np.zeros_like(tau0)
    if base.phi_change:
        bodies = sorted(base.phi_change)
        y, _ = arm.regressor(q, qd, qdd, bodies)
        pred += y @ np.concatenate([base.phi_change[b] for b in bodies])
    cols = {e.key: e for e in candidate_effects(arm, q, qd, qdd, tau0, inertial=False,
                                                transmission=transmission)}
    for f in base.effects:
        pred += cols[f.key].columns @ np.array([f.params[p].value for p in f.params])
    return pred


def validate(arm: Arm, diag: DynamicDiagnosis, log: TorqueLog,
             options: DynamicsOptions | None = None) -> Validation:
    """Score ``diag``'s corrected model on ``log`` (module docstring); ``options`` as the
    diagnosis's (its filter window and fit rate)."""
    opt = options or DynamicsOptions()
    if log.n_joints != arm.n:
        raise InputError(f"validate: {log.source} has {log.n_joints} joints, the model "
                         f"{arm.n}")
    sigma = torque_noise(log, opt.window_s)
    s, stride = decimated_states(log, opt)
    tau0 = model_torques(arm, log, s, stride)
    pred = _prediction(arm, diag, s.q, s.qd, s.qdd, tau0, log.transmission)
    b_raw = s.tau_raw - tau0
    base = None
    if diag.baseline is not None:
        r = b_raw - _baseline_prediction(arm, diag.baseline, s.q, s.qd, s.qdd, tau0,
                                         log.transmission)
        base = np.sqrt(np.mean(r * r, axis=0))
    return Validation(log.source, sigma, np.sqrt(np.mean(b_raw**2, axis=0)),
                      np.sqrt(np.mean((b_raw - pred) ** 2, axis=0)), int(b_raw.shape[0]),
                      log.measured & diag.measured, base)
