"""Pose accuracy and repeatability in the manner of ISO 9283 (positions and orientations).

For every commanded pose measured at least ``min_repeats`` times (the same joint values under
different pose ids; ISO 9283 uses 30 cycles), with x_j the attained positions of one tool point
(j = 1..m), x_bar their barycentre and x_c the commanded position:

    AP = |x_bar - x_c|                           (position accuracy, ISO 9283 7.2.1)
    l_j = |x_j - x_bar|,  RP = l_bar + 3 S_l,    S_l = sqrt(sum (l_j - l_bar)^2 / (m - 1))
                                                 (position repeatability, 7.2.2)

Orientations (when the measurements carry ``qw..qz``; 7.2.1 and 7.2.2 for a, b, c): with
R_c the commanded orientation and R_j the attained ones, (a_j, b_j, c_j) = log(R_c^T R_j)
are the deviation angles about the commanded frame's x, y, z axes (rad, small angles), and

    AP_a = mean a_j (likewise b, c),   RP_a = 3 S_a,   S_a = sqrt(sum (a_j - a_bar)^2 / (m - 1)).

The commanded position is what a model predicts for the commanded joints: the
registration-only model gives the accuracy of the uncalibrated robot, the calibrated one that
after calibration. The repeatability needs no model and says how much of a remaining gap no
calibration can remove (it includes the instrument's noise).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from zrp.arrays import F64
from zrp.calibration.calibrated import CalibratedRobot, PoseConditions
from zrp.errors import InputError
from zrp.gap.data.measurements import Measurements

__all__ = ["PoseAccuracy", "pose_accuracy"]



@dataclass(frozen=True, eq=False)
class PoseAccuracy:
    """AP and RP per repeated commanded pose (K poses).

    Attributes:
        point: the tool point.
        q: the commanded joint values, shape (K, n).
        repeats: measurements per pose (K,).
        ap: position accuracy per pose, shape (K,) (length unit).
        rp: position repeatability per pose, shape (K,) (length unit).
        ap_abc, rp_abc: orientation accuracy and repeatability about x, y, z per pose, shape
            (K, 3) (rad), or None (no measured orientations).
    """

    point: str
    q: F64
    repeats: NDArray[np.int64]
    ap: F64
    rp: F64
    ap_abc: F64 | None = None
    rp_abc: F64 | None = None

    def __post_init__(self) -> None:
        K = len(self.q)
        if self.ap.shape != (K,) or self.rp.shape != (K,) or self.repeats.shape != (K,):
            raise InputError("PoseAccuracy: arrays do not match the number of poses")
        for name in ("ap_abc", "rp_abc"):
            v = getattr(self, name)
            if v is not None and np.shape(v) != (K, 3):
                raise InputError(f"PoseAccuracy: {name} must have shape ({K}, 3)")

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {
            "point": self.point, "poses": len(self.q), "repeats": self.repeats.tolist(),
            "ap": self.ap.tolist(), "rp": self.rp.tolist(),
            "ap_max": float(self.ap.max()), "rp_max": float(self.rp.max())}
        if self.ap_abc is not None and self.rp_abc is not None:
            out.update({"ap_abc_rad": self.ap_abc.tolist(), "rp_abc_rad": self.rp_abc.tolist()})
        return out


def pose_accuracy(meas: Measurements, cal: CalibratedRobot, point: str, *,
                  min_repeats: int = 3, probe_rotation: ArrayLike | None = None
                  ) -> PoseAccuracy:
    """ISO 9283 AP and RP of ``point`` on the repeated poses of ``meas`` (see the module doc).

    Args:
        meas: measurements (instrument frame as ``cal``), poses repeated under different ids.
        cal: the model that gives the commanded positions (:meth:`CalibratedRobot.predict`,
            each repeat with its own approach direction, temperature and load).
        point: the tool point label.
        min_repeats: poses measured fewer times are skipped.
        probe_rotation: R_t, the measured frame on the hand (commanded orientation
            R_b R'_n R_t), shape (3, 3) (default identity: the hand frame is measured; e.g.
            :attr:`zrp.gap.fit.fullpose.FullPoseFit.probe_rotation`).

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
    dev = None
    if meas.quat is not None:
        rt = np.eye(3) if probe_rotation is None else np.asarray(probe_rotation, dtype=float)
        if rt.shape != (3, 3):
            raise InputError(f"probe_rotation: expected shape (3, 3), got {rt.shape}")
        rc = cal.predict_rotation(q, cond, "instrument" if meas.frame == "instrument"
                                  else "base") @ rt
        rj = Rotation.from_quat(np.asarray(meas.quat)[rows][:, [1, 2, 3, 0]]).as_matrix()
        dev = Rotation.from_matrix(np.swapaxes(rc, 1, 2) @ rj).as_rotvec()
    ap, rp, reps, qs, ap_o, rp_o = [], [], [], [], [], []
    for g in keep:
        sel = group == g
        if dev is not None:
            ap_o.append(dev[sel].mean(axis=0))
            rp_o.append(3.0 * dev[sel].std(axis=0, ddof=1))
        x = meas.xyz[rows[sel]]
        bar = x.mean(axis=0)
        ap.append(float(np.linalg.norm(bar - pred[sel].mean(axis=0))))
        lj = np.linalg.norm(x - bar, axis=1)
        rp.append(float(lj.mean() + 3.0 * lj.std(ddof=1)))
        reps.append(int(sel.sum()))
        qs.append(q[sel][0])
    return PoseAccuracy(point, np.array(qs), np.array(reps), np.array(ap), np.array(rp),
                        np.array(ap_o) if dev is not None else None,
                        np.array(rp_o) if dev is not None else None)
