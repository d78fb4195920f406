"""Robot logs as robots record them (issue 44): ROS bags (ROS 2 MCAP and SQLite 3, ROS 1)
of one simulated UR5e run read into the TorqueLog, and the diagnosis, of the CSV export of the
same samples; joints matched to the model's by name (alphabetical order as UR's driver
publishes, names the model lacks, missing chain joints, joints off the chain); signed torque
constants; bags without joint states refused naming their topics."""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest

from tests.gap.dynamics._bags import header, write_bag, write_ros_csv
from zrp.errors import InputError
from zrp.gap.dynamics.bag import load_bag_log, read_log
from zrp.gap.dynamics.diagnosis import diagnose_dynamics
from zrp.gap.dynamics.joints import match_joints

pytest.importorskip("rosbags")

ALPHABETICAL = [2, 1, 0, 3, 4, 5]  # elbow, shoulder_lift, shoulder_pan, wrist_1..3


@pytest.fixture(scope="module")
def run(ur5e, ur5e_command):
    """A 3 s UR5e log with viscous friction on joint 3 that the model lacks."""
    from sim.studies.dynamics.truth import HiddenDynamics, simulate

    hidden = HiddenDynamics(viscous=np.array([0, 0, 4.0, 0, 0, 0]))
    log = simulate(ur5e, hidden, ur5e_command, 3.0, noise_nm=np.full(6, 0.05), seed=1)
    return dataclasses.replace(log, qc=None)


@pytest.fixture(scope="module")
def files(run, ur5e, tmp_path_factory):
    d = tmp_path_factory.mktemp("bags")
    names = ur5e.joint_names
    return {"mcap": write_bag(run, names, d / "run_mcap", kind="mcap"),
            "sqlite3": write_bag(run, names, d / "run_db3", kind="sqlite3"),
            "ros1": write_bag(run, names, d / "run.bag", kind="ros1"),
            "csv": write_ros_csv(run, names, d / "run.csv"),
            "alpha": write_bag(run, names, d / "alpha.mcap", kind="mcap", order=ALPHABETICAL),
            "alpha_csv": write_ros_csv(run, names, d / "alpha.csv", order=ALPHABETICAL)}


def _same(a, b, tol=1e-9):
    for f in ("t", "q", "qd", "tau"):
        np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=0, atol=tol, err_msg=f)
    assert a.joint_names == b.joint_names and a.segments == b.segments


def _same_diagnosis(d1, d2):
    assert [(e.name, e.joint) for e in d1.effects] == [(e.name, e.joint) for e in d2.effects]
    for e1, e2 in zip(d1.effects, d2.effects, strict=True):
        for k, v in e1.params.items():
            w = e2.params[k]
            np.testing.assert_allclose([v.value, v.low, v.high], [w.value, w.low, w.high],
                                       rtol=1e-9, atol=1e-9)
    for f in ("rms_before", "rms_after", "noise_nm"):
        np.testing.assert_allclose(getattr(d1, f), getattr(d2, f), rtol=1e-9, atol=1e-12)


def test_mcap_db3_and_ros1_bags_read_as_the_csv_export(files, ur5e, run):
    csv = read_log(files["csv"])
    for kind in ("mcap", "sqlite3", "ros1"):
        log = read_log(files[kind])
        _same(log, csv)
        np.testing.assert_allclose(log.q, run.q, rtol=0, atol=1e-12)
        assert log.joint_names == tuple(ur5e.joint_names) and log.torque_from == "tau"
        assert "JointState" in log.conditioning.columns
        assert "header stamps" in log.conditioning.clock
    # the .mcap / .db3 file of a bag folder, and the file alone (no metadata.yaml beside it)
    lone = files["csv"].parent / "lone.mcap"
    shutil.copy(next(files["mcap"].glob("*.mcap")), lone)
    _same(read_log(next(files["mcap"].glob("*.mcap"))), csv)
    _same(read_log(lone), csv)
    lone_db3 = files["csv"].parent / "lone.db3"
    shutil.copy(next(files["sqlite3"].glob("*.db3")), lone_db3)
    _same(read_log(lone_db3), csv)


def test_bag_and_csv_give_the_same_diagnosis(files, ur5e):
    d_csv = diagnose_dynamics(ur5e, match_joints(read_log(files["csv"]), ur5e.joint_names))
    assert d_csv.effects and d_csv.effects[0].name == "viscous" and d_csv.effects[0].joint == 2
    for kind in ("mcap", "ros1"):
        log = match_joints(read_log(files[kind]), ur5e.joint_names)
        _same_diagnosis(diagnose_dynamics(ur5e, log), d_csv)


def test_alphabetical_joint_order_gives_the_model_order_answer(files, ur5e):
    ref = match_joints(read_log(files["mcap"]), ur5e.joint_names)
    for key in ("alpha", "alpha_csv"):
        raw = read_log(files[key])
        assert raw.joint_names[0] == "elbow_joint"
        log = match_joints(raw, ur5e.joint_names)
        _same(log, ref)
        assert any("reordered by name" in j for j in log.conditioning.joints)
    d_alpha = diagnose_dynamics(ur5e, match_joints(read_log(files["alpha"]), ur5e.joint_names))
    _same_diagnosis(d_alpha, diagnose_dynamics(ur5e, ref))


def test_messages_in_another_order_are_mapped_by_name(run, ur5e, tmp_path):
    # every other message lists the joints in another order: each is mapped by name
    names = ur5e.joint_names
    half = run.first(run.n_samples // 2)
    a = write_bag(half, names, tmp_path / "a.mcap", kind="mcap")
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    mixed = tmp_path / "mixed.mcap"
    with Reader(a) as r, Writer(mixed, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for k, (c, t_ns, raw) in enumerate(r.messages()):
            msg = store.deserialize_cdr(raw, c.msgtype)
            if k % 2:
                o = ALPHABETICAL
                msg = type(msg)(header=msg.header, name=[msg.name[i] for i in o],
                                position=msg.position[o], velocity=msg.velocity[o],
                                effort=msg.effort[o])
            w.write(conn, t_ns, store.serialize_cdr(msg, c.msgtype))
    _same(read_log(mixed), read_log(a))


def test_a_name_the_model_lacks_and_a_missing_chain_joint_are_refused_by_name(run, ur5e,
                                                                               tmp_path):
    names = list(ur5e.joint_names)
    odd = [*names[:5], "tool_changer_joint"]
    log = read_log(write_bag(run, odd, tmp_path / "odd.mcap", kind="mcap"))
    with pytest.raises(InputError, match=r"names joint\(s\) tool_changer_joint that the "
                                         "model lacks"):
        match_joints(log, names)
    five = dataclasses.replace(run, q=run.q[:, :5], qd=run.qd[:, :5], tau=run.tau[:, :5])
    log = read_log(write_bag(five, names[:5], tmp_path / "five.bag", kind="ros1"))
    with pytest.raises(InputError, match="has no joint wrist_3_joint of the arm's chain"):
        match_joints(log, names)


def test_joints_off_the_chain_are_left_out_and_named(run, ur5e, tmp_path):
    names = list(ur5e.joint_names)
    seven = np.column_stack([run.q, np.full(run.n_samples, 0.01)])
    log7 = dataclasses.replace(run, q=seven, qd=np.column_stack([run.qd, 0 * run.t]),
                               tau=np.column_stack([run.tau, 0 * run.t]))
    bag = write_bag(log7, [*names, "finger_joint"], tmp_path / "grip.mcap", kind="mcap",
                    order=[6, *ALPHABETICAL])
    raw = read_log(bag)
    assert raw.joint_names[0] == "finger_joint" and 0 in raw.unmeasured
    log = match_joints(raw, names, model_joints=[*names, "finger_joint"])
    _same(log, match_joints(read_log(write_bag(run, names, tmp_path / "r.mcap")), names))
    assert not log.unmeasured and not log.conditioning.excluded
    assert any("left out: joint(s) finger_joint" in j for j in log.conditioning.describe()
               if j.startswith("joints:") or "left out" in j)


def test_an_unnamed_log_says_how_its_columns_were_taken(run, ur5e):
    log = match_joints(run, ur5e.joint_names)
    assert "1 = shoulder_pan_joint" in log.conditioning.joints[0]
    with pytest.raises(InputError, match=r"6 joints \(unnamed columns\), but the arm has 5"):
        match_joints(run, ur5e.joint_names[:5])


def test_negative_torque_constants_are_applied(run, ur5e, tmp_path):
    # the bag's efforts are the drives' currents; two drives count the other way
    kt = np.array([12.0, -8.7, 9.0, -4.5, 3.0, 3.0])
    currents = dataclasses.replace(run, tau=run.tau / kt)
    bag = write_bag(currents, ur5e.joint_names, tmp_path / "i.mcap", kind="mcap")
    log = load_bag_log(bag, torque_constant=kt.tolist())
    np.testing.assert_allclose(log.tau, run.tau, rtol=1e-12, atol=1e-12)
    assert log.torque_from == "current" and "-8.7" in log.conditioning.columns
    with pytest.raises(InputError, match=r"zero for joint 3 \(elbow_joint\)"):
        load_bag_log(bag, torque_constant=[1, 1, 0, 1, 1, 1])


def test_unmeasured_joints_in_a_bag_are_named_after_reordering(run, ur5e, tmp_path):
    tau = run.tau.copy()
    tau[:, 3] = 0.0  # wrist_1 not logged
    bag = write_bag(dataclasses.replace(run, tau=tau), ur5e.joint_names, tmp_path / "u.mcap",
                    order=ALPHABETICAL)
    log = match_joints(read_log(bag), ur5e.joint_names)
    assert list(log.unmeasured) == [3] and "exactly zero" in log.unmeasured[3]
    assert log.conditioning.excluded[0].startswith("joint 4 (wrist_1_joint)")


def test_zero_stamps_fall_back_to_the_log_time(run, ur5e, tmp_path):
    bag = write_bag(run, ur5e.joint_names, tmp_path / "z.mcap", zero_stamps=True)
    log = read_log(bag)
    np.testing.assert_allclose(log.t, read_log(write_ros_csv(run, ur5e.joint_names,
                                                             tmp_path / "z.csv")).t, atol=1e-9)
    assert "log (receive) times" in log.conditioning.clock


def _points(store):
    cls = store.types["geometry_msgs/msg/PointStamped"]
    pt = store.types["geometry_msgs/msg/Point"]
    return [(10**9 + k * 10**7, cls(header=header(store, 10**9 + k * 10**7),
                                    point=pt(x=0.1 * k, y=0.0, z=0.0))) for k in range(3)]


def test_a_bag_without_joint_states_is_refused_naming_its_topics(run, ur5e, tmp_path):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    p = tmp_path / "tracker_only.mcap"
    with Writer(p, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection("/tracker/point", "geometry_msgs/msg/PointStamped",
                             typestore=store)
        for t_ns, m in _points(store):
            w.write(c, t_ns, store.serialize_cdr(m, "geometry_msgs/msg/PointStamped"))
    with pytest.raises(InputError, match=r"no sensor_msgs/msg/JointState topic; its topics: "
                                         r"/tracker/point \(geometry_msgs/msg/PointStamped\)"):
        read_log(p)


def test_several_joint_state_topics_need_topic(run, ur5e, tmp_path):
    names = ur5e.joint_names
    two = write_bag(run, names, tmp_path / "two.bag", kind="ros1",
                    extra=[("/arm/joint_states", "sensor_msgs/msg/JointState", lambda s: [])])
    with pytest.raises(InputError, match=r"2 sensor_msgs/msg/JointState topics "
                                         r"\(/arm/joint_states, /joint_states\); choose one "
                                         "with --topic"):
        read_log(two)
    assert read_log(two, topic="/joint_states").n_samples == run.n_samples
    with pytest.raises(InputError, match=r"--topic /nope: two\.bag has no such topic"):
        read_log(two, topic="/nope")
    with pytest.raises(InputError, match="not a ROS bag"):
        read_log(write_ros_csv(run, names, tmp_path / "x.csv"), topic="/joint_states")
