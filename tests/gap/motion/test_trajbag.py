"""diagnose-motion from a ROS bag (issue 44): the joint states and a tracker's PointStamped
(or PoseStamped) topic, each on its own clock, read into the same Trajectory as the trajectory
CSV of the same samples (its tq column: the one aligner, zrp.gap.motion.data.joints_at)."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from tests.gap.dynamics._bags import header
from tests.measured import tracked_tool_point
from zrp.errors import InputError
from zrp.gap.motion import load_trajectory
from zrp.gap.motion.paths import exercise_moves
from zrp.gap.motion.trajbag import load_trajectory_bag

pytest.importorskip("rosbags")

T0 = 1_700_000_000_000_000_000
S = 400  # 2 s at 200 Hz


@pytest.fixture(scope="module")
def puma():
    return zrp.load_model("puma")


@pytest.fixture(scope="module")
def streams(puma):
    """Tracker stamps and points (mm), joint stamps (their own clock, 3.7 ms earlier, jittered)
    and joint values; stamps in ns."""
    rng = np.random.default_rng(4)
    moves = exercise_moves(np.radians([0, -20, 30, 0, 60, 0]), rng, moves=4)
    t_tr = T0 + 10**9 + np.arange(S, dtype=np.int64) * 5_000_000
    t_tr += rng.integers(-200_000, 200_000, S)
    t_q = t_tr - 3_700_000 + rng.integers(-300_000, 300_000, S)
    q = moves((t_q - T0) * 1e-9)
    xyz = tracked_tool_point(puma, moves((t_tr - T0) * 1e-9 - 0.002), rng)
    return t_tr, xyz, t_q, q


def _write(path, puma, streams, *, kind="mcap", pose=False, order=None):
    from rosbags.typesys import Stores, get_typestore

    t_tr, xyz, t_q, q = streams
    names = list(puma.joint_names)
    order = list(range(len(names))) if order is None else order
    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    ty = store.types
    js_type = "sensor_msgs/msg/JointState"
    pt_type = "geometry_msgs/msg/PoseStamped" if pose else "geometry_msgs/msg/PointStamped"

    def point(k):
        x, y, z = (xyz[k] / 1000.0).tolist()
        if pose:
            p = ty["geometry_msgs/msg/Pose"](
                position=ty["geometry_msgs/msg/Point"](x=x, y=y, z=z),
                orientation=ty["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
            return ty[pt_type](header=header(store, int(t_tr[k])), pose=p)
        return ty[pt_type](header=header(store, int(t_tr[k])),
                           point=ty["geometry_msgs/msg/Point"](x=x, y=y, z=z))

    def joint(k):
        return ty[js_type](header=header(store, int(t_q[k])), name=[names[i] for i in order],
                           position=q[k, order], velocity=np.zeros(0), effort=np.zeros(0))

    ser = store.serialize_ros1 if kind == "ros1" else store.serialize_cdr
    if kind == "ros1":
        from rosbags.rosbag1 import Writer as W1
        writer = W1(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer
        writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    with writer as w:
        cj = w.add_connection("/joint_states", js_type, typestore=store)
        cp = w.add_connection("/tracker/tool", pt_type, typestore=store)
        # each message logged a little after its stamp, on the recorder's clock
        for k in range(S):
            w.write(cj, int(t_q[k]) + 150_000, ser(joint(k), js_type))
            w.write(cp, int(t_tr[k]) + 900_000, ser(point(k), pt_type))
    return path


def _csv(path, puma, streams):
    t_tr, xyz, t_q, q = streams
    origin = min(int(t_tr[0]), int(t_q[0]))
    n = puma.n
    cols = np.column_stack([(t_tr - origin) * 1e-9, q, xyz / 1000.0 * 1000.0,
                            (t_q - origin) * 1e-9])
    head = ",".join(["t", *[f"q{k + 1}" for k in range(n)], "x", "y", "z", "tq"])
    np.savetxt(path, cols, delimiter=",", fmt="%.17g", header=head, comments="")
    return path


def _same(a, b):
    np.testing.assert_allclose(a.t, b.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.xyz, b.xyz, rtol=0, atol=1e-9)


@pytest.mark.parametrize(("kind", "pose"), [("mcap", False), ("ros1", True)])
def test_a_bag_gives_the_trajectory_of_the_csv(puma, streams, tmp_path, kind, pose):
    ref = load_trajectory(_csv(tmp_path / "run.csv", puma, streams), puma)
    bag = _write(tmp_path / ("run.bag" if kind == "ros1" else "run.mcap"), puma, streams,
                 kind=kind, pose=pose, order=[5, 4, 3, 2, 1, 0])
    traj = load_trajectory_bag(bag, puma)
    assert traj.n_samples == ref.n_samples == S
    _same(traj, ref)


def test_a_bag_lacking_a_model_joint_or_a_tracker_is_refused(puma, streams, tmp_path):
    _, _, t_q, q = streams
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    p = tmp_path / "no_tracker.mcap"
    with Writer(p, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for k in range(3):
            msg = store.types["sensor_msgs/msg/JointState"](
                header=header(store, int(t_q[k])), name=["q1", "q2"], position=q[k, :2],
                velocity=np.zeros(0), effort=np.zeros(0))
            w.write(c, int(t_q[k]), store.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
    with pytest.raises(InputError, match=r"lack the model's joint\(s\) q3, q4, q5, q6"):
        load_trajectory_bag(p, puma)
    p2 = tmp_path / "two.mcap"
    with Writer(p2, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for k in range(3):
            msg = store.types["sensor_msgs/msg/JointState"](
                header=header(store, int(t_q[k])), name=list(puma.joint_names),
                position=q[k], velocity=np.zeros(0), effort=np.zeros(0))
            w.write(c, int(t_q[k]), store.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
    with pytest.raises(InputError, match=r"no geometry_msgs/msg/PointStamped or "
                                         r"geometry_msgs/msg/PoseStamped topic; its topics: "
                                         r"/joint_states \(sensor_msgs/msg/JointState\)"):
        load_trajectory_bag(p2, puma)


def test_diagnose_motion_reads_a_bag(puma, streams, tmp_path, capsys):
    import json

    from zrp.cli import main

    bag = _write(tmp_path / "run.mcap", puma, streams)
    code = main(["diagnose-motion", "--model", "puma", "--data", str(bag), "--topic",
                 "/joint_states", "--point-topic", "/tracker/tool", "--effects", "sync_delay",
                 "--out", str(tmp_path / "o"), "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    doc = json.loads(captured.out)
    # the tracker saw the arm 2 ms late: found through the two clocks
    assert doc["effects"] == ["sync_delay"], doc["verdict"]
    (p,) = doc["final"]["parameters"]
    assert p["value"] == pytest.approx(0.002, abs=4 * p["stderr"] + 2e-5)
