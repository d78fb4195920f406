"""The torque log of a ROS bag's ``sensor_msgs/msg/JointState`` topic, and :func:`read_log`,
the one reader of a log as a robot records it (a bag, else the CSV of
:func:`zrp.gap.dynamics.data.load_torque_log`).

* **Topic.** ``topic`` (``--topic``), else the bag's only JointState topic; several, or none
  (the bag's topics and types are named), are refused (:mod:`zrp.gap.data.rosbag`).
* **Joints by name.** The first message's ``name`` list is the log's joints, in its order
  (:attr:`TorqueLog.joint_names`, matched to the model's by
  :func:`zrp.gap.dynamics.joints.match_joints`). A later message naming them in another
  order (or with more joints) is mapped by name; one lacking any of them is skipped, counted
  and named in the notes.
* **Clock.** The header stamps; when they are all zero (a driver that leaves them unset),
  the bag's log (receive) time. Taken from the first message, in s; then the conditioning of
  a CSV log (:func:`zrp.gap.dynamics.timebase.condition`: repeats, gaps, segments; the "line"
  of a sample is its message number on the topic).
* **Values.** ``position`` (rad, m), ``velocity`` (when every message has one per joint, else
  derived), ``effort`` as the torques (N m, N); with ``torque_constant`` the efforts are the
  drives' currents (A; UR's driver publishes them) times the signed constants, in the log's
  joint order.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.rosbag import JOINT_STATE, is_bag, read_topic, stamp_ns
from zrp.gap.dynamics.data import (
    MAX_ROWS,
    TorqueLog,
    excluded_notes,
    load_torque_log,
    torque_constants,
)
from zrp.gap.dynamics.frozen import frozen_joints
from zrp.gap.dynamics.logcheck import unmeasured_joints
from zrp.gap.dynamics.timebase import Conditioning, clock, condition
from zrp.gap.dynamics.transmission import Transmission

__all__ = ["load_bag_log", "read_log"]


class _States:
    """The JointState messages gathered per joint, in the first message's joint order."""

    def __init__(self, src: str) -> None:
        self.src = src
        self.names: tuple[str, ...] = ()
        self.stamp: list[int] = []
        self.logged: list[int] = []
        self.rows: list[tuple[Any, Any, Any]] = []
        self.numbers: list[int] = []
        self.skipped = 0
        self.other: tuple[str, ...] = ()
        self.topic = ""

    def add(self, k: int, t_log: int, msg: Any) -> None:
        names = tuple(str(x) for x in msg.name)
        if not self.names:
            if not names or len(set(names)) != len(names):
                raise InputError(f"{self.src}: message 1 on the JointState topic names "
                                 f"{list(names)}; expected distinct joint names")
            self.names = names
        pos = {nm: i for i, nm in enumerate(names)}
        if not all(nm in pos for nm in self.names):
            self.skipped += 1
            self.other = self.other or names
            return
        idx = [pos[nm] for nm in self.names]
        self.rows.append(tuple(_pick(getattr(msg, f), idx, len(names), f, k, self.src)
                               for f in ("position", "velocity", "effort")))
        self.stamp.append(stamp_ns(msg))
        self.logged.append(t_log)
        self.numbers.append(k)


def _pick(values: Any, idx: list[int], n: int, field: str, k: int, src: str) -> F64 | None:
    a = np.asarray(values, dtype=float).ravel()
    if a.size == 0 and field == "velocity":
        return None
    if a.size != n:
        raise InputError(f"{src}: JointState message {k}: {a.size} {field} value(s) for its "
                         f"{n} joint names")
    return a[idx]


def _gather(path: str | os.PathLike[str], topic: str | None, max_rows: int | None,
            src: str) -> _States:
    states = _States(src)
    for k, (t_log, msg) in enumerate(read_topic(path, (JOINT_STATE,), topic=topic,
                                                max_messages=max_rows), start=1):
        states.add(k, t_log, msg)
    if len(states.rows) < 2:
        raise InputError(f"{src}: {len(states.rows)} JointState message(s) naming the joints; "
                         "a torque log needs a time series")
    return states


def _clock(st: _States) -> tuple[F64, str]:
    stamps = np.asarray(st.stamp, dtype=np.int64)
    which = "header stamps"
    if not stamps.any():
        stamps, which = np.asarray(st.logged, dtype=np.int64), "log (receive) times"
        which += " (the header stamps are all zero)"
    t = (stamps - stamps[0]).astype(float) * 1e-9
    t, _ = clock(t, "s", "s", "stamp", st.src)
    return t, (f"clock: the messages' {which}, ns, taken from the first message "
               f"({int(stamps[0])} ns)")


def load_bag_log(path: str | os.PathLike[str], *, topic: str | None = None,
                 torque_constant: Sequence[float] | None = None,
                 max_rows: int | None = MAX_ROWS) -> TorqueLog:
    """The :class:`TorqueLog` of the bag's JointState topic (module docstring).

    Raises:
        InputError: naming the bag, topic, message or joint of the first problem.
    """
    src = Path(path).name
    st = _gather(path, topic, max_rows, src)
    t, said = _clock(st)
    q = np.array([r[0] for r in st.rows])
    has_qd = all(r[1] is not None for r in st.rows)
    qd = np.array([r[1] for r in st.rows]) if has_qd else None
    effort = np.array([r[2] for r in st.rows])
    lines = np.asarray(st.numbers, dtype=np.int64)
    values = np.hstack([x for x in (q, qd, effort) if x is not None])
    kept, segments, rec = condition(t, values, lines, src)
    n = len(st.names)
    tau, tfrom = effort[kept], "tau"
    if torque_constant is not None:
        kt = torque_constants(torque_constant, n, st.names)
        tau, tfrom = tau * kt, "current"
    q = q[kept]
    frozen, frozen_notes = frozen_joints(t[kept], q, tau, lines[kept])
    unmeasured = {**frozen, **unmeasured_joints(q, tau)}
    if len(unmeasured) == n:
        raise InputError(f"{src}: no joint's torque is data: " + "; ".join(
            f"joint {k + 1} ({st.names[k]}): {w}" for k, w in sorted(unmeasured.items())))
    dropped = rec.pop("dropped")
    if st.skipped:
        dropped += (f"{st.skipped} JointState message(s) not naming all of the first "
                    f"message's joints (e.g. {', '.join(st.other) or 'none'}) skipped",)
    cond = Conditioning(columns=_describe(st, has_qd, tfrom, torque_constant), clock=said,
                        excluded=(*excluded_notes(unmeasured, st.names), *frozen_notes),
                        dropped=dropped,
                        **rec)  # type: ignore[arg-type]
    return TorqueLog(t[kept], q, None if qd is None else qd[kept], tau, None, None,
                     lines[kept], src, tfrom, segments if len(segments) > 1 else (),
                     unmeasured, st.names, cond)


def _describe(st: _States, has_qd: bool, tfrom: str,
              torque_constant: Sequence[float] | None) -> str:
    text = (f"ROS bag {st.src}: {JOINT_STATE} messages, {len(st.names)} joints named "
            f"{', '.join(st.names)}; positions, "
            + ("velocities, " if has_qd else "no velocities (derived), "))
    if tfrom == "current" and torque_constant is not None:
        kts = ", ".join(f"{nm} {k:g}" for nm, k in zip(st.names, torque_constant, strict=True))
        return text + f"efforts as motor currents (A) times the torque constants ({kts} N m/A)"
    return text + "efforts as the joint torques (N m)"


def read_log(path: str | os.PathLike[str], *, topic: str | None = None,
             torque_constant: Sequence[float] | None = None, n_joints: int | None = None,
             max_rows: int | None = MAX_ROWS, transmission: Transmission | None = None,
             rate_hz: float | None = None) -> TorqueLog:
    """A torque log as the robot recorded it: a ROS bag (:func:`load_bag_log`; by suffix
    ``.bag``, ``.mcap``, ``.db3`` or a folder holding ``metadata.yaml``), else a CSV log
    (:func:`zrp.gap.dynamics.data.load_torque_log`); ``topic`` is for bags only."""
    if is_bag(path):
        if transmission is not None or rate_hz is not None:
            raise InputError(f"{'--transmission' if transmission else '--rate'}: "
                             f"{Path(path).name} is a ROS bag (its own clock, joint-side "
                             "joint_states); these options are for CSV logs")
        return load_bag_log(path, topic=topic, torque_constant=torque_constant,
                            max_rows=max_rows)
    if topic is not None:
        raise InputError(f"--topic {topic}: {Path(path).name} is not a ROS bag (.bag, .mcap, "
                         ".db3 or a folder with metadata.yaml); a CSV log has no topics")
    return load_torque_log(path, torque_constant=torque_constant, n_joints=n_joints,
                           max_rows=max_rows, transmission=transmission, rate_hz=rate_hz)
