"""The corrected model's torques (eq. V1): what a diagnosis predicts along any states, with
the values it fitted, nothing refitted. One definition, used by the validation on a second
log (:mod:`.validation`) and by whatever checks that a written corrected model (the MJCF,
:mod:`mjcf.corrected`) reproduces the diagnosis.

Along states (q, qd, qdd) with the model's torques tau0 (:func:`.diagnosis.model_torques`)::

    tau_corrected = tau0 + sum_b Y_b (phi_b - phi0_b) + sum_e Y_e theta_e          (eq. V1)

the first sum over every body the diagnosis changed (:attr:`DynamicDiagnosis.bodies`: link
inertias, a part not on the arm, a link's mass, a payload; exact, eq. R2), the second over
every other found effect (its columns, :mod:`.effects`, times its fitted values).
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.effects import candidate_effects
from zrp.gap.dynamics.results import Baseline, DynamicDiagnosis
from zrp.gap.dynamics.transmission import Transmission

__all__ = ["baseline_torques", "corrected_torques", "effect_torques"]


def effect_torques(arm: Arm, diag: DynamicDiagnosis, q: F64, qd: F64, qdd: F64, tau0: F64,
                   transmission: Transmission | None = None) -> dict[str, F64]:
    """Each term of eq. V1 along the states, (S, n) each: ``"bodies"`` (every changed body
    at once, when there is one) and each found effect not held in a body, by its key
    (``transmission``: the log's, for the coupled motors' effects)."""
    keys = {e.key for e in diag.effects}
    cols = {e.key: e for e in candidate_effects(arm, q, qd, qdd, tau0, inertial=False,
                                                transmission=transmission)
            if e.key in keys}
    out: dict[str, F64] = {}
    in_bodies = {k for c in diag.bodies.values() for k in c.effects}
    if diag.bodies:
        bodies = sorted(diag.bodies)
        y, _ = arm.regressor(q, qd, qdd, bodies)
        out["bodies"] = y @ np.concatenate([diag.bodies[b].phi - diag.bodies[b].phi0
                                            for b in bodies])
    for f in diag.effects:
        if f.key in in_bodies:
            continue
        e = cols.get(f.key)
        if e is None:
            raise InputError(f"prediction: effect {f.key} cannot be evaluated on this arm")
        out[f.key] = e.columns @ np.array([f.params[p].value for p in e.params])
    return out


def corrected_torques(arm: Arm, diag: DynamicDiagnosis, q: F64, qd: F64, qdd: F64,
                      tau0: F64, transmission: Transmission | None = None) -> F64:
    """Eq. V1 without tau0: the torques the diagnosis's effects add along the states (S, n)."""
    return sum(effect_torques(arm, diag, q, qd, qdd, tau0, transmission).values(),
               np.zeros_like(tau0))


def baseline_torques(arm: Arm, base: Baseline, q: F64, qd: F64, qdd: F64, tau0: F64,
                     transmission: Transmission | None = None) -> F64:
    """The standard identification's torques along the states, without tau0 (its link
    combinations as the change of every body's phi, its joint and motor terms by their
    columns)."""
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
