"""ROS bags written by rosbags' own writers (ROS 2 MCAP and SQLite 3, ROS 1) from a
:class:`TorqueLog` with joint names, and the CSV export of the same samples, for the bag
reader's tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

T0_NS = 1_700_000_000_000_000_000  # an epoch clock, as a robot's stamps are


def header(store, stamp_ns):
    """A std_msgs Header of ``stamp_ns`` (ROS 1's has a ``seq``)."""
    types = store.types
    stamp = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000,
                                                  nanosec=stamp_ns % 1_000_000_000)
    cls = types["std_msgs/msg/Header"]
    return cls(stamp=stamp, frame_id="", **({"seq": 0} if "seq" in cls.__dataclass_fields__
                                            else {}))


def _msg(store, names, q, qd, tau, stamp_ns):
    types = store.types
    header_ = header(store, stamp_ns)
    return types["sensor_msgs/msg/JointState"](
        header=header_, name=list(names), position=np.asarray(q, dtype=float),
        velocity=np.zeros(0) if qd is None else np.asarray(qd, dtype=float),
        effort=np.asarray(tau, dtype=float))


def stamps_ns(log):
    return T0_NS + np.round(log.t * 1e9).astype(np.int64)


def _rows(log, names, order):
    """(stamp, names, q, qd, tau) per sample, the joints in ``order`` (indices into names)."""
    ns = stamps_ns(log)
    nm = [names[k] for k in order]
    for i in range(log.n_samples):
        qd = None if log.qd is None else log.qd[i, order]
        yield int(ns[i]), nm, log.q[i, order], qd, log.tau[i, order]


def write_bag(log, names, path: Path, *, kind="mcap", order=None, topic="/joint_states",
              zero_stamps=False, extra=()):
    """``log`` as a JointState topic of a bag of ``kind`` (mcap, sqlite3, ros1); ``order``:
    the joints' order in the messages (default the log's); ``extra``: (topic, msgtype, msgs
    as (t_ns, msg)) further topics. Returns the path written."""
    from rosbags.typesys import Stores, get_typestore

    order = list(range(len(names))) if order is None else list(order)
    if kind == "ros1":
        from rosbags.rosbag1 import Writer as Writer1

        store = get_typestore(Stores.ROS1_NOETIC)
        with Writer1(path) as w:
            conn = w.add_connection(topic, "sensor_msgs/msg/JointState", typestore=store)
            extra_conns = [(w.add_connection(tp, mt, typestore=store), mt, msgs)
                           for tp, mt, msgs in extra]
            for st, nm, q, qd, tau in _rows(log, names, order):
                msg = _msg(store, nm, q, qd, tau, 0 if zero_stamps else st)
                w.write(conn, st, store.serialize_ros1(msg, "sensor_msgs/msg/JointState"))
            for c, mt, msgs in extra_conns:
                for t_ns, m in msgs(store):
                    w.write(c, t_ns, store.serialize_ros1(m, mt))
        return path
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conn = w.add_connection(topic, "sensor_msgs/msg/JointState", typestore=store)
        extra_conns = [(w.add_connection(tp, mt, typestore=store), mt, msgs)
                       for tp, mt, msgs in extra]
        for st, nm, q, qd, tau in _rows(log, names, order):
            msg = _msg(store, nm, q, qd, tau, 0 if zero_stamps else st)
            w.write(conn, st, store.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
        for c, mt, msgs in extra_conns:
            for t_ns, m in msgs(store):
                w.write(c, t_ns, store.serialize_cdr(m, mt))
    return path


def write_ros_csv(log, names, path: Path, *, order=None):
    """The same samples as a ROS-style CSV export (``t [s]``, ``position_<joint>`` ...)."""
    order = list(range(len(names))) if order is None else list(order)
    t = (stamps_ns(log) - T0_NS) * 1e-9
    cols = [("t [s]", t)]
    for group, block in (("position", log.q), ("velocity", log.qd), ("effort", log.tau)):
        if block is not None:
            cols += [(f"{group}_{names[k]}", block[:, k]) for k in order]
    np.savetxt(path, np.column_stack([c[1] for c in cols]), delimiter=",", fmt="%.17g",
               header=",".join(c[0] for c in cols), comments="")
    return path
