"""The corrected model scored on another log (``--validate LOG2``): the diagnosis is fitted on
one run; its effects, with the values fitted there, predict the torques of a second run the
fit never saw (another excitation, another day). Per joint and overall RMS before (the
model) and after (the corrected model), against that log's own noise floor.

The prediction along the second log's states is the corrected model's torques (eq. V1,
:func:`zrp.gap.dynamics.prediction.corrected_torques`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

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
from zrp.gap.dynamics.prediction import baseline_torques, corrected_torques

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


def validate(arm: Arm, diag: DynamicDiagnosis, log: TorqueLog,
             options: DynamicsOptions | None = None) -> Validation:
    """Score ``diag``'s corrected model on ``log`` (module docstring); ``options`` as the
    diagnosis's (its filter window and fit rate)."""
    # the diagnosis's filter (its window may have been chosen from its log)
    opt = replace(options or DynamicsOptions(), window_s=diag.window_s)
    if log.n_joints != arm.n:
        raise InputError(f"validate: {log.source} has {log.n_joints} joints, the model "
                         f"{arm.n}")
    sigma = torque_noise(log, opt.window_s)
    s, stride = decimated_states(log, opt)
    tau0 = model_torques(arm, log, s, stride)
    pred = corrected_torques(arm, diag, s.q, s.qd, s.qdd, tau0, log.transmission)
    b_raw = s.tau_raw - tau0
    base = None
    if diag.baseline is not None:
        r = b_raw - baseline_torques(arm, diag.baseline, s.q, s.qd, s.qdd, tau0,
                                     log.transmission)
        base = np.sqrt(np.mean(r * r, axis=0))
    return Validation(log.source, sigma, np.sqrt(np.mean(b_raw**2, axis=0)),
                      np.sqrt(np.mean((b_raw - pred) ** 2, axis=0)), int(b_raw.shape[0]),
                      log.measured & diag.measured, base)
