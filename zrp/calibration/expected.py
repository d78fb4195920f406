"""What a compensation is expected to achieve, honestly: the accuracy the diagnosis measured on
its withheld poses, never the calibrated model's agreement with itself.

A compensation solves the calibrated model to its targets, so its predicted residual is the
solver's convergence (1e-10 mm), not an accuracy. What the compensated robot will reach is
what the calibrated model achieved on poses it was not fitted to: the diagnosis's withheld RMS
(``withheld_rms`` of compensation.json), valid within the joint ranges the calibration
measured (:attr:`~zrp.calibration.conditions.Conditions.joint_ranges`); outside them the model
is extrapolated and the error is larger by an amount these data cannot say. Each target is
flagged when a command lies outside those ranges (``outside_measured``, as the guards of
:mod:`zrp.calibration.guards` decide).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.compensation import Compensation

__all__ = ["expected_accuracy", "expected_words"]

#: most target ids named in the words.
SHOWN = 5


def expected_accuracy(cal: CalibratedRobot, comp: Compensation) -> dict[str, Any]:
    """The expected accuracy of ``comp`` (module docstring) as a JSON-ready dict:
    ``expected_rms`` (the withheld RMS, with the learned residual term when the calibration
    carries one; None when the file records none), ``basis``,
    ``outside_measured_targets`` (ids of the targets outside the measured ranges), ``inside``
    (targets within them), ``correction_rms`` (how far the calibrated model moves the
    program's targets: the uncompensated predicted error) and ``solve_rms`` (the solver's
    residual: convergence, not accuracy)."""
    outside = [t for t, o in zip(comp.target_ids, comp.outside_measured, strict=True) if o]
    ranges = None if cal.conditions is None else cal.conditions.joint_ranges
    learned = cal.learned is not None
    return {"expected_rms": (cal.learned.withheld_rms_hybrid if cal.learned is not None
                             else cal.withheld_rms),
            "basis": "the diagnosis's RMS error on its withheld poses (poses the calibration "
                     "was not fitted to)" + (", with its learned residual term" if learned
                                            else "") + ", valid within the measured joint ranges",
            "measured_joint_ranges": None if ranges is None else [
                None if r is None else list(r) for r in ranges],
            "inside": len(comp.target_ids) - len(outside), "outside_measured_targets": outside,
            "correction_rms": float(np.sqrt(np.mean(comp.uncompensated ** 2))),
            "solve_rms": float(np.sqrt(np.mean(comp.residual ** 2)))}


def expected_words(acc: dict[str, Any], unit: str) -> str:
    """One paragraph for the command line."""
    n = acc["inside"] + len(acc["outside_measured_targets"])
    if acc["expected_rms"] is None:
        head = (f"{n} targets: expected error unknown (this calibration file records no "
                "withheld RMS; run zrp calibrate again to record it)")
    else:
        head = (f"{n} targets: expected error {acc['expected_rms']:.4g} {unit} RMS, what the "
                "diagnosis measured on withheld poses, within the measured joint ranges")
    out = acc["outside_measured_targets"]
    if out:
        shown = ", ".join(out[:SHOWN]) + (" ..." if len(out) > SHOWN else "")
        head += (f"; {len(out)} target(s) outside those ranges ({shown}; flagged "
                 "outside_measured): larger there, by an amount the data cannot say")
    elif acc["measured_joint_ranges"] is not None:
        head += "; every target within them"
    return (f"{head}. The calibration moves the targets by {acc['correction_rms']:.4g} {unit} "
            f"RMS; the solve converged to {acc['solve_rms']:.2g} {unit} (the model agreeing "
            "with itself, not an accuracy).")
