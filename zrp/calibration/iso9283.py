"""Pose accuracy and repeatability in the manner of ISO 9283 (positions only).

For every commanded pose measured at least ``min_repeats`` times (the same joint values under
different pose ids; ISO 9283 uses 30 cycles), with x_j the attained positions of one tool point
(j = 1..m), x_bar their barycentre and x_c the commanded position:

    AP = |x_bar - x_c|                           (position accuracy, ISO 9283 7.2.1)
    l_j = |x_j - x_bar|,  RP = l_bar + 3 S_l,    S_l = sqrt(sum (l_j - l_bar)^2 / (m - 1))
                                                 (position repeatability, 7.2.2)

The commanded position is what a model predicts for the commanded joints: the
registration-only model gives the accuracy of the uncalibrated robot, the calibrated one that
after calibration. The repeatability needs no model and says how much of a remaining gap no
calibration can remove (it includes the instrument's noise).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.calibration.calibrated import CalibratedRobot, PoseConditions
from zrp.errors import InputError
from zrp.gap.data import Measurements

__all__ = ["PoseAccuracy", "pose_accuracy"]

F64 = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PoseAccuracy:
    """AP and RP per repeated commanded pose (K poses).

    Attributes:
        point: the tool point.
        q: the commanded joint values, shape (K, n).
        repeats: measurements per pose (K,).
        ap: position accuracy per pose, shape (K,) (length unit).
        rp: position repeatability per pose, shape (K,) (length unit).
    """

    point: str
    q: F64
    repeats: NDArray[np.int64]
    ap: F64
    rp: F64

    def __post_init__(self) -> None:
        K = len(self.q)
        if self.ap.shape != (K,) or self.rp.shape != (K,) or self.repeats.shape != (K,):
            raise InputError("PoseAccuracy: arrays do not match the number of poses")

    def to_dict(self) -> dict[str, object]:
        return {"point": self.point, "poses": len(self.q), "repeats": self.repeats.tolist(),
                "ap": self.ap.tolist(), "rp": self.rp.tolist(),
                "ap_max": float(self.ap.max()), "rp_max": float(self.rp.max())}


def pose_accuracy(meas: Measurements, cal: CalibratedRobot, point: str, *,
                  min_repeats: int = 3) -> PoseAccuracy:
    """ISO 9283 AP and RP of ``point`` on the repeated poses of ``meas`` (see the module doc).

    Args:
        meas: measurements (instrument frame as ``cal``), poses repeated under different ids.
        cal: the model that gives the commanded positions (:meth:`CalibratedRobot.predict`,
            each repeat with its own approach direction, temperature and load).
        point: the tool point label.
        min_repeats: poses measured fewer times are skipped.

    Raises:
        InputError: unknown point, or no pose repeated ``min_repeats`` times.
    """
    if point not in meas.point_labels:
        raise InputError(f"point: {point!r} not measured; points: {list(meas.point_labels)}")
    rows = np.flatnonzero(np.asarray(meas.point) == point)
    q = meas.q[rows]
    _, group, counts = np.unique(q, axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    keep = np.flatnonzero(counts >= min_repeats)
    if not keep.size:
        raise InputError(f"meas: no pose is measured at least {min_repeats} times (min_repeats)"
                         "; repeat poses to measure repeatability")
    pidx = meas.pose_index[rows]
    cond = PoseConditions(direction=meas.approach_direction()[pidx],
                          temp=meas.per_pose("temp")[pidx] if meas.temp is not None else None,
                          load=meas.per_pose("load")[pidx] if meas.load is not None else None)
    pred = cal.predict(q, point, cond, frame="instrument" if meas.frame == "instrument"
                       else "base")
    ap, rp, reps, qs = [], [], [], []
    for g in keep:
        sel = group == g
        x = meas.xyz[rows[sel]]
        bar = x.mean(axis=0)
        ap.append(float(np.linalg.norm(bar - pred[sel].mean(axis=0))))
        lj = np.linalg.norm(x - bar, axis=1)
        rp.append(float(lj.mean() + 3.0 * lj.std(ddof=1)))
        reps.append(int(sel.sum()))
        qs.append(q[sel][0])
    return PoseAccuracy(point, np.array(qs), np.array(reps), np.array(ap), np.array(rp))
