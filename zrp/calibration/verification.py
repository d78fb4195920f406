"""What a calibration achieved on a fresh real measurement (``zrp verify --data``).

The fresh set is a measurement CSV as ``zrp diagnose`` reads (pose, point, q1..qn, x, y, z
[, t, temp, load, qw..qz]) of the robot after calibration: either the uncompensated robot at
any joint values, or the compensated one at the commands ``zrp compensate`` wrote. In both
cases the position the calibration says the robot reaches at the recorded joint values is
:meth:`~zrp.calibration.calibrated.CalibratedRobot.predict` (for a compensated command, the
target it was solved for), so the achieved error of each measured point is

    e_i = |x_i - predict(q_i, point_i)|    (3-D, length unit)

and the set's RMS, 95th percentile and maximum are what the robot achieves, against the
diagnosis's prediction (its withheld RMS, :mod:`.expected`). Poses whose joint values lie
outside the ranges the calibration measured (:mod:`.guards`) are counted apart: the prediction
holds within them. Where the set repeats poses (the same joint values, at least
``min_repeats`` times), ISO 9283 pose accuracy AP and repeatability RP per tool point
(:mod:`.iso9283`).

The instrument frame is the calibration's (the tracker has not moved); with ``reregister``
the instrument-from-base transform is fitted again to the fresh set (a rigid fit of the
predicted points to the measured ones, said in the result), for a tracker set up anew - it
absorbs six degrees of freedom of the error, so the figures are then slightly optimistic.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.calibration.calibrated import CalibratedRobot, PoseConditions
from zrp.calibration.compensation import GravityFn
from zrp.calibration.guards import outside_measured
from zrp.calibration.iso9283 import PoseAccuracy, pose_accuracy
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements

__all__ = ["Verification", "verify_measurements"]


@dataclass(frozen=True, eq=False)
class Verification:
    """The achieved accuracy on a fresh set (module docstring).

    Attributes:
        errors: 3-D position error per measured row (length unit), shape (R,).
        points: the tool point of each row (R,).
        outside: the row's pose lies outside the measured joint ranges (R,).
        predicted_rms: the diagnosis's withheld RMS (with its learned term when kept), or
            None (not recorded).
        iso: ISO 9283 AP and RP per tool point with repeated poses.
        reregistered: the instrument frame was fitted again; shift: how far the fresh
            registration moved the measured points' centre (length unit), 0 otherwise.
        n_poses: distinct pose ids.
    """

    errors: F64
    points: NDArray[np.str_]
    outside: NDArray[np.bool_]
    predicted_rms: float | None
    iso: tuple[PoseAccuracy, ...]
    reregistered: bool
    shift: float
    n_poses: int

    @staticmethod
    def _stats(e: F64) -> dict[str, float | int | None]:
        if e.size == 0:
            return {"n": 0, "rms": None, "p95": None, "max": None}
        return {"n": int(e.size), "rms": float(np.sqrt(np.mean(e**2))),
                "p95": float(np.percentile(e, 95)), "max": float(e.max())}

    def to_dict(self) -> dict[str, Any]:
        inside = self._stats(self.errors[~self.outside])
        allrows = self._stats(self.errors)
        ratio = (None if self.predicted_rms in (None, 0.0) or inside["rms"] is None
                 else float(inside["rms"]) / float(self.predicted_rms))  # type: ignore[arg-type]
        return {"all": allrows, "within_measured_ranges": inside,
                "outside_measured_ranges": self._stats(self.errors[self.outside]),
                "predicted_rms": self.predicted_rms, "achieved_to_predicted": ratio,
                "per_point": {str(p): self._stats(self.errors[self.points == p])
                              for p in dict.fromkeys(self.points.tolist())},
                "iso9283": [{"ap_mean": float(a.ap.mean()), "rp_mean": float(a.rp.mean()),
                             **a.to_dict()} for a in self.iso],
                "reregistered": self.reregistered, "reregistration_shift": self.shift,
                "poses": self.n_poses, "rows": int(self.errors.size)}

    def words(self, unit: str) -> str:
        """A paragraph for the command line and the report page."""
        d = self.to_dict()
        a, w = d["all"], d["within_measured_ranges"]
        text = (f"{d['rows']} measured points on {d['poses']} fresh poses: RMS error "
                f"{a['rms']:.4g} {unit}, 95th percentile {a['p95']:.4g} {unit}, maximum "
                f"{a['max']:.4g} {unit}.")
        if self.predicted_rms is not None and w["rms"] is not None:
            text += (f" Within the measured joint ranges ({w['n']} points) RMS {w['rms']:.4g} "
                     f"{unit} against the {self.predicted_rms:.4g} {unit} the diagnosis "
                     f"predicted on its withheld poses ({d['achieved_to_predicted']:.2f}x).")
        o = d["outside_measured_ranges"]
        if o["n"]:
            text += (f" Outside those ranges ({o['n']} points) RMS {o['rms']:.4g} {unit}: the "
                     "calibration is extrapolated there.")
        for acc in self.iso:
            text += (f" ISO 9283 on {len(acc.q)} repeated poses of {acc.point}: accuracy AP "
                     f"{acc.ap.mean():.4g} {unit} mean ({acc.ap.max():.4g} max), "
                     f"repeatability RP {acc.rp.mean():.4g} {unit} mean ({acc.rp.max():.4g} "
                     "max).")
        if not self.iso:
            text += " No pose is repeated: ISO 9283 repeatability needs repeated poses."
        if self.reregistered:
            text += (f" The instrument frame was fitted again to this set (the points' centre "
                     f"moved {self.shift:.3g} {unit}): slightly optimistic.")
        return text


def _conditions(meas: Measurements, gravity_torque: GravityFn | None) -> PoseConditions:
    pidx = meas.pose_index
    return PoseConditions(
        direction=meas.approach_direction()[pidx],
        gravity_torque=None if gravity_torque is None else gravity_torque(meas.q),
        temp=None if meas.temp is None else np.asarray(meas.temp, dtype=float),
        load=None if meas.load is None else np.asarray(meas.load, dtype=float))


def _rigid(a: F64, b: F64) -> tuple[F64, F64]:
    """R, t minimizing |R a + t - b| (Kabsch)."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cb - r @ ca


def _predict(cal: CalibratedRobot, meas: Measurements, cond: PoseConditions) -> F64:
    frame = "instrument" if meas.frame == "instrument" else "base"
    pred = np.empty_like(meas.xyz)
    point = np.asarray(meas.point)
    for p in meas.point_labels:
        rows = np.flatnonzero(point == p)
        sub = PoseConditions(*(None if v is None else np.asarray(v)[rows] for v in (
            cond.direction, cond.gravity_torque, cond.temp, cond.load)))
        pred[rows] = cal.predict(meas.q[rows], p, sub, frame=frame)
    return pred


def verify_measurements(cal: CalibratedRobot, meas: Measurements, *, reregister: bool = False,
                        min_repeats: int = 3, gravity_torque: GravityFn | None = None
                        ) -> Verification:
    """The achieved accuracy of ``cal`` on the fresh measurements ``meas`` (module docstring);
    ``gravity_torque``: q (R, n) -> torques (N m), for a compliance identified with an MJCF.

    Raises:
        InputError: a point the calibration does not know, or a frame other than its own.
    """
    unknown = [p for p in meas.point_labels if p not in cal.tool_labels]
    if unknown:
        raise InputError(f"{meas.source}: point(s) {', '.join(unknown)} are not tool points of "
                         f"the calibration ({', '.join(cal.tool_labels)}); measure those")
    if meas.frame == "instrument" and cal.frame != "instrument":
        raise InputError(f"{meas.source}: instrument-frame data, but the calibration's data "
                         "were in the base frame (no instrument registration): pass --frame "
                         "base with base-frame positions")
    pred = _predict(cal, meas, _conditions(meas, gravity_torque))
    shift = 0.0
    if reregister and meas.frame == "instrument":
        r, t = _rigid(pred, meas.xyz)
        moved = pred @ r.T + t
        shift = float(np.linalg.norm(moved.mean(0) - pred.mean(0)))
        rb = r @ np.asarray(cal.base_rotation)
        cal = dataclasses.replace(cal, base_rotation=rb,
                                  base_translation=r @ np.asarray(cal.base_translation) + t)
        pred = moved
    errors = np.linalg.norm(meas.xyz - pred, axis=1)
    outside = outside_measured(meas.q, cal.conditions).any(axis=1)
    iso = []
    for p in meas.point_labels:
        try:
            iso.append(pose_accuracy(meas, cal, p, min_repeats=min_repeats))
        except InputError:  # no pose of this point repeated min_repeats times
            continue
    predicted = (cal.learned.withheld_rms_hybrid if cal.learned is not None
                 else cal.withheld_rms)
    if predicted is not None and not math.isfinite(predicted):
        predicted = None
    return Verification(errors, np.asarray(meas.point).astype(str), outside, predicted,
                        tuple(iso), reregister and meas.frame == "instrument", shift,
                        len(meas.pose_ids))
