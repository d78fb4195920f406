"""A trajectory measurement from a ROS bag: the robot's ``sensor_msgs/msg/JointState`` topic
and an instrument's ``geometry_msgs/msg/PointStamped`` or ``PoseStamped`` topic (its
position), each on its own clock, aligned as the trajectory CSV's ``tq`` column is
(:func:`zrp.gap.motion.data.joints_at`: the joint values at the tracker's times by a cubic
spline through the joint stream).

* **Topics.** ``topic`` (``--topic``) and ``point_topic`` (``--point-topic``), else the bag's
  only topic of each type (:mod:`zrp.gap.data.rosbag`; several, or none, refused naming
  them).
* **Joints by name.** Every joint of the model must be named in the joint-state messages
  (the names the model lacks, and the model's joints the messages lack, are named in the
  error); the values are taken in the model's order, each message mapped by name.
* **Clocks.** Each stream's header stamps (its log time when they are all zero), both taken
  from the earlier first stamp (s). Tracker samples more than one joint step outside the
  joint stream's time span (no joint values to interpolate) are left out.
* **Units.** ROS's SI: positions in m and joint values in rad (m for slides), converted to the
  model's length unit.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.choices import MAX_ROWS
from zrp.gap.data.rosbag import JOINT_STATE, POINT, POSE, read_topic, stamp_ns
from zrp.gap.motion.data import Trajectory, check_rate, joints_at
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit

__all__ = ["load_trajectory_bag"]


def _order(names: list[str], model: Manipulator, src: str) -> list[int]:
    want = list(model.joint_names)
    lacking = [j for j in want if j not in names]
    if lacking:
        odd = [nm for nm in names if nm not in want]
        raise InputError(f"{src}: the JointState messages lack the model's joint(s) "
                         f"{', '.join(lacking)} (they name {', '.join(names)}"
                         + (f"; not in the model: {', '.join(odd)}" if odd else "") + ")")
    return [names.index(j) for j in want]


def _joints(path: str | os.PathLike[str], model: Manipulator, topic: str | None,
            max_rows: int | None, src: str) -> tuple[np.ndarray, np.ndarray, F64]:
    """The joint stream: stamps (ns), log times (ns), values (K, n) in the model's order."""
    stamps, logged, rows = [], [], []
    for k, (t_log, msg) in enumerate(read_topic(path, (JOINT_STATE,), topic=topic,
                                                option="--topic", max_messages=max_rows),
                                     start=1):
        names = [str(x) for x in msg.name]
        pos = np.asarray(msg.position, dtype=float).ravel()
        if pos.size != len(names):
            raise InputError(f"{src}: JointState message {k}: {pos.size} position value(s) "
                             f"for its {len(names)} joint names")
        rows.append(pos[_order(names, model, src)])
        stamps.append(stamp_ns(msg))
        logged.append(t_log)
    if len(rows) < 2:
        raise InputError(f"{src}: {len(rows)} JointState message(s); the joint values need "
                         "a stream")
    return np.asarray(stamps, dtype=np.int64), np.asarray(logged, dtype=np.int64), \
        np.array(rows)


def _position(msg: Any) -> tuple[float, float, float]:
    p = msg.point if hasattr(msg, "point") else msg.pose.position
    return float(p.x), float(p.y), float(p.z)


def _points(path: str | os.PathLike[str], topic: str | None, max_rows: int | None
            ) -> tuple[np.ndarray, np.ndarray, F64]:
    stamps, logged, xyz = [], [], []
    for t_log, msg in read_topic(path, (POINT, POSE), topic=topic, option="--point-topic",
                                 max_messages=max_rows):
        xyz.append(_position(msg))
        stamps.append(stamp_ns(msg))
        logged.append(t_log)
    return np.asarray(stamps, dtype=np.int64), np.asarray(logged, dtype=np.int64), \
        np.array(xyz, dtype=float).reshape(-1, 3)


def _clock(stamps: np.ndarray, logged: np.ndarray) -> np.ndarray:
    return stamps if stamps.any() else logged


def load_trajectory_bag(path: str | os.PathLike[str], model: Manipulator, *,
                        topic: str | None = None, point_topic: str | None = None,
                        frame: str = "instrument", max_rows: int | None = MAX_ROWS
                        ) -> Trajectory:
    """The :class:`Trajectory` of a bag's joint states and tracker points (module docstring).

    Raises:
        InputError: naming the bag, topic, message or joint of the first problem.
    """
    src = Path(path).name
    js, jl, q = _joints(path, model, topic, max_rows, src)
    ps, pl, xyz = _points(path, point_topic, max_rows)
    tq_ns, tp_ns = _clock(js, jl), _clock(ps, pl)
    origin = min(int(tq_ns[0]), int(tp_ns[0]) if tp_ns.size else int(tq_ns[0]))
    tq = (tq_ns - origin).astype(float) * 1e-9
    tp = (tp_ns - origin).astype(float) * 1e-9
    step = float(np.median(np.diff(tq)))
    inside = (tp >= tq[0] - step) & (tp <= tq[-1] + step)
    number = np.flatnonzero(inside).astype(np.int64) + 1  # message number on the point topic
    tp, xyz = tp[inside], xyz[inside]
    check_rate(tp, number, src)
    unit = 1.0 / metres_per_unit(model.length_unit)
    slide = np.asarray(model.prismatic, dtype=bool)
    q = np.where(slide, q * unit, q)
    qs = joints_at(tp, tq, q, src, np.arange(1, tq.size + 1, dtype=np.int64))
    return Trajectory(tp, qs, xyz * unit, ("p1",), frame, number, src)
