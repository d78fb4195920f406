"""Logs as controllers write them (issue 32 part 2): a clean simulated 7-joint log and its
defective twin (clock jitter, 5 % repeated rows, eight gaps of 2-9 ms, torque quantisation)
read into states that agree with the closed form as closely as the clean twin's do; every
controller naming form read into the same TorqueLog; unmeasured joints excluded and named."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics import TorqueLog, derive_states, load_torque_log, write_torque_log
from zrp.gap.dynamics.diagnosis import torque_noise

N = 7
SIGMA = 0.02  # torque noise, N m
RNG = np.random.default_rng(7)
AMP = RNG.uniform(0.3, 0.8, N)
W = 2 * math.pi * RNG.uniform(0.2, 0.9, N)
PH = RNG.uniform(0, 2 * math.pi, N)


def truth(t):
    """q, qd, qdd and the noise-free torque of the synthetic arm at times t."""
    x = W * t[:, None] + PH
    q = AMP * np.sin(x) + 0.2 * AMP * np.sin(2.3 * x)
    qd = AMP * W * np.cos(x) + 0.46 * AMP * W * np.cos(2.3 * x)
    qdd = -AMP * W**2 * np.sin(x) - 1.058 * AMP * W**2 * np.sin(2.3 * x)
    return q, qd, qdd, 2.0 * qdd + 0.5 * qd + 3.0 * np.sin(q)


def clean_log(seconds=8.0):
    t = np.arange(int(seconds * 1000)) / 1000.0
    q, _, _, tau = truth(t)
    noise = np.random.default_rng(1).normal(0, SIGMA, tau.shape)
    return TorqueLog(t, q + np.random.default_rng(2).normal(0, 1e-6, q.shape), None, tau + noise)


def defective_csv(path, seconds=8.0, quantum=0.005):
    """The twin as libfranka logs it: time in ms with jittering steps, 5 % of rows written
    twice, eight gaps of 2-9 ms, torques quantised to ``quantum`` N m."""
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.8e-3, 1.6e-3, int(seconds * 1000 / 1.2)))
    gaps = rng.choice(np.arange(200, t.size - 200), 8, replace=False)
    for g in sorted(gaps):
        t[g:] += rng.uniform(2e-3, 9e-3)
    q, _, _, tau = truth(t)
    tau = np.round((tau + rng.normal(0, SIGMA, tau.shape)) / quantum) * quantum
    q = q + rng.normal(0, 1e-6, q.shape)
    head = ",".join(["time", *(f"q_{k}" for k in range(N)), *(f"tau_J_{k}" for k in range(N)),
                     *(f"O_T_EE_{k}" for k in range(3))])
    out, repeats = [head], 0
    for i in range(t.size):
        row = ",".join(repr(float(v)) for v in [t[i] * 1e3, *q[i], *tau[i], 0.1, 0.2, 0.3])
        out.append(row)
        if rng.random() < 0.05:
            out.append(row)
            repeats += 1
    path.write_text("\n".join(out) + "\n")
    return path, repeats


def _state_errors(s, margin):
    """RMS error of qd, qdd and the filtered torque against the closed form, inside each
    segment (``margin`` samples from its ends left out)."""
    _, qd, qdd, tau = truth(s.t)
    keep = np.zeros(s.t.size, bool)
    for k in np.unique(s.segment):
        idx = np.flatnonzero(s.segment == k)
        keep[idx[margin:-margin]] = True
    rms = lambda a, b: float(np.sqrt(np.mean((a[keep] - b[keep]) ** 2)))  # noqa: E731
    return rms(s.qd, qd), rms(s.qdd, qdd), rms(s.tau, tau)


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    d = tmp_path_factory.mktemp("twins")
    clean = load_torque_log(write_torque_log(clean_log(), d / "clean.csv"))
    path, repeats = defective_csv(d / "franka.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bad = load_torque_log(path)
    return clean, bad, repeats


def test_the_defective_twin_is_read_as_is(twins):
    _, bad, repeats = twins
    c = bad.conditioning
    assert "libfranka" in c.columns and "O_T_EE_0" in c.columns
    assert "read as ms" in c.clock
    assert c.repeats == repeats > 0 and c.conflicts == 0
    assert len(c.gaps) == 8 and all(2e-3 <= g.seconds <= 9e-3 + 1.6e-3 for g in c.gaps)
    assert len(bad.segments) == 9 and bad.segments[-1][1] == bad.n_samples
    assert 0.8e-3 <= c.step_min_s and c.step_max_s <= 1.6e-3
    assert np.all(np.diff(bad.t) > 0) and not bad.unmeasured
    text = "\n".join(c.describe())
    assert "8 gap(s)" in text and "9 segments" in text and "no resampling" in text


def test_the_twins_states_agree_within_the_noise(twins):
    clean, bad, _ = twins
    s_clean, s_bad = derive_states(clean), derive_states(bad)
    e_clean, e_bad = _state_errors(s_clean, 60), _state_errors(s_bad, 60)
    # the torques: both filtered to well below the raw noise
    assert e_bad[2] < 0.5 * SIGMA and e_clean[2] < 0.5 * SIGMA
    # velocities and accelerations: the defective twin within 1.5x the clean twin's error
    # (fewer samples per window at a 1.2 ms mean step), never a gap's jump
    for a, b in zip(e_bad, e_clean, strict=True):
        assert a < 1.5 * b + 1e-3
    assert np.max(np.abs(s_bad.qdd - truth(s_bad.t)[2])) < 20 * e_bad[1]
    # the noise floor: the same to within 10 % (quantisation adds 0.0014 N m in quadrature)
    n_clean, n_bad = torque_noise(clean, 0.1), torque_noise(bad, 0.1)
    np.testing.assert_allclose(n_bad, n_clean, rtol=0.1)
    np.testing.assert_allclose(n_clean, SIGMA, rtol=0.1)


def test_a_gap_is_never_differentiated_across():
    """Two segments whose positions jump by 1 rad across a 5 ms gap: the accelerations next
    to the gap stay those of each segment (a filter across it would see the jump)."""
    t = np.r_[np.arange(500), np.arange(505, 1005)] / 1000.0
    q = np.sin(t)[:, None] + np.where(t > 0.5, 1.0, 0.0)[:, None]
    log = TorqueLog(t, q, None, np.cos(3 * t)[:, None], segments=((0, 500), (500, 1000)))
    s = derive_states(log, window_s=0.05)
    np.testing.assert_allclose(s.qdd[:, 0], -np.sin(s.t), atol=1e-3)  # a jump: ~1e3
    assert set(np.unique(s.segment)) == {0, 1}
    assert s.every(10).t.size == 100 and np.all(s.every(10).index % 10 == 0)


def test_segments_shorter_than_the_window_are_left_out_and_named():
    t = np.r_[np.arange(300), np.arange(310, 340), np.arange(350, 700)] / 1000.0
    log = TorqueLog(t, np.sin(t)[:, None], None, np.cos(t)[:, None],
                    segments=((0, 300), (300, 330), (330, 680)))
    s = derive_states(log, window_s=0.05)
    assert s.t.size == 650 and len(s.dropped) == 1 and "samples 300-329" in s.dropped[0]


# --- every controller form into the same TorqueLog ---------------------------------------

def _reference():
    t = np.arange(600) / 1000.0
    q, qd, _, tau = truth(t)
    return t, q[:, :3], qd[:, :3], tau[:, :3]


def _table(header, cols):
    return ",".join(header) + "\n" + "\n".join(",".join(repr(float(v)) for v in row)
                                              for row in np.column_stack(cols)) + "\n"


def _forms():
    t, q, qd, tau = _reference()
    j = range(3)
    yield "zrp", _table(["t [s]", *(f"q{k + 1} [rad]" for k in j), *(f"qd{k + 1}" for k in j),
                         *(f"tau{k + 1}" for k in j)], [t, q, qd, tau]), {}
    for fmt in ("q_{}", "q[{}]", "q{}"):
        yield "libfranka", _table(["time [ms]", *(fmt.format(k) for k in j),
                                   *(fmt.replace("q", "dq").format(k) for k in j),
                                   *(fmt.replace("q", "tau_J").format(k) for k in j),
                                   *(fmt.replace("q", "q_d").format(k) for k in j)],
                                  [t * 1e3, q, qd, tau, q]), {}
    yield "UR RTDE", _table(["timestamp", *(f"actual_q_{k}" for k in j),
                             *(f"actual_qd_{k}" for k in j),
                             *(f"actual_current_{k}" for k in j), *(f"target_q_{k}" for k in j),
                             "robot_mode"], [t + 1.5e6, q, qd, tau / 10.0, q, 0 * t + 7]), \
        {"torque_constant": [10.0] * 3}
    yield "KUKA", _table(["ZeitInSec", *(f"MeasuredJointPosition_{k + 1}" for k in j),
                          *(f"MeasuredTorque_{k + 1}" for k in j)], [t, q, tau]), {}
    yield "KUKA", _table(["time", *(f"A{k + 1}" for k in j), *(f"MeasuredTorque_A{k + 1}"
                                                               for k in j)],
                         [t, np.degrees(q), tau]), {}
    yield "ROS", _table(["__time", *(f"/joint_states/position/panda_joint{k + 1}" for k in j),
                         *(f"/joint_states/velocity/panda_joint{k + 1}" for k in j),
                         *(f"/joint_states/effort/panda_joint{k + 1}" for k in j)],
                        [t, q, qd, tau]), {}
    names = ["shoulder", "elbow", "wrist"]
    yield "ROS", _table(["time", *(f"position_{n}" for n in names),
                         *(f"effort_{n}" for n in names)], [t, q, tau]), {}


def test_every_controller_form_reads_into_the_same_log(tmp_path):
    t, q, qd, tau = _reference()
    for k, (form, text, kw) in enumerate(_forms()):
        p = tmp_path / f"f{k}.csv"
        p.write_text(text)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            log = load_torque_log(p, n_joints=3, **kw)
        assert form in log.conditioning.columns, (form, log.conditioning.columns)
        np.testing.assert_allclose(log.t, t, atol=1e-9, err_msg=form)
        np.testing.assert_allclose(log.q, q, atol=1e-12, err_msg=form)
        np.testing.assert_allclose(log.tau, tau, atol=1e-12, err_msg=form)
        if log.qd is not None:
            np.testing.assert_allclose(log.qd, qd, atol=1e-12, err_msg=form)
    assert "absolute clock" in load_torque_log(tmp_path / "f4.csv", torque_constant=[10.0] * 3
                                               ).conditioning.clock


def test_ros_names_are_kept_in_log_order(tmp_path):
    t, q, _, tau = _reference()
    p = tmp_path / "ros.csv"
    p.write_text(_table(["time", "position_elbow", "position_shoulder", "position_wrist",
                         "effort_wrist", "effort_elbow", "effort_shoulder"],
                        [t, q, tau[:, [2, 0, 1]]]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = load_torque_log(p)
    assert log.joint_names == ("elbow", "shoulder", "wrist")
    np.testing.assert_allclose(log.tau, tau)  # efforts matched to positions by name


def test_rostopic_echo_export(tmp_path):
    """``rostopic echo -p``: ns stamps (epoch), names as text cells, 0-based indices."""
    t, q, qd, tau = _reference()
    stamp = (1_700_000_000 + t) * 1e9
    head = ["%time", "field.header.seq", "field.header.stamp", "field.header.frame_id",
            *(f"field.name{k}" for k in range(3)), *(f"field.position{k}" for k in range(3)),
            *(f"field.velocity{k}" for k in range(3)), *(f"field.effort{k}" for k in range(3))]
    rows = [",".join([f"{s + 2e5:.0f}", str(i), f"{s:.0f}", "", "j_a", "j_b", "j_c",
                      *(repr(float(v)) for v in [*q[i], *qd[i], *tau[i]])])
            for i, s in enumerate(stamp)]
    p = tmp_path / "echo.csv"
    p.write_text(",".join(head) + "\n" + "\n".join(rows) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = load_torque_log(p)
    assert log.joint_names == ("j_a", "j_b", "j_c")
    assert "field.header.stamp" in log.conditioning.columns
    np.testing.assert_allclose(log.t, t, atol=1e-6)
    np.testing.assert_allclose(log.tau, tau)


def test_a_header_of_no_known_form_lists_the_forms(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("stamp_x,angle_a,angle_b,load_a,load_b\n0,0,0,0,0\n1,1,1,1,1\n")
    with pytest.raises(InputError, match=r"accepted: zrp: .*libfranka.*UR RTDE.*KUKA.*ROS"):
        load_torque_log(p)


# --- unmeasured joints ----------------------------------------------------------------------

def test_unmeasured_joints_are_excluded_and_named(tmp_path):
    t, q, _, tau = _reference()
    tau = tau.copy()
    tau[:, 1] = 0.0
    q = q.copy()
    q[:, 2] = 0.25
    log = TorqueLog(t, q, None, tau)
    p = write_torque_log(log, tmp_path / "u.csv")
    back = load_torque_log(p)
    assert set(back.unmeasured) == {1, 2}
    assert "torque exactly zero" in back.unmeasured[1]
    assert "never moves" in back.unmeasured[2]
    assert back.measured.tolist() == [True, False, False]
    assert any("joint 2" in e for e in back.conditioning.excluded)
    tau[:, 0] = 1.5
    p = write_torque_log(TorqueLog(t, q, None, tau), tmp_path / "none.csv")
    with pytest.raises(InputError, match="no joint's torque is data"):
        load_torque_log(p)


def test_first_keeps_segments_and_record(twins):
    _, bad, _ = twins
    k = bad.segments[2][0] + 10
    part = bad.first(k)
    assert part.n_samples == k and len(part.segments) == 3 and part.segments[-1] == (k - 10, k)
    assert part.conditioning is bad.conditioning


def test_the_real_time_axis_fit_is_savitzky_golay_and_exact_for_cubics():
    """localpoly's general path: on a uniform grid it is scipy's savgol_filter (an independent
    reference); on a jittered grid it reproduces a cubic and its derivatives exactly."""
    from scipy.signal import savgol_filter

    from zrp.gap.dynamics.localpoly import _chunk, local_fit

    rng = np.random.default_rng(4)
    t = np.arange(600) / 1000.0
    y = rng.normal(size=(600, 2))
    coef, _ = _chunk(t, y, np.arange(600), 51, 3, 0.025)
    for d in (0, 1, 2):
        ref = savgol_filter(y, 51, 3, deriv=d, delta=1e-3, axis=0, mode="interp")
        np.testing.assert_allclose(coef[:, d, :] * math.factorial(d) / 0.025**d, ref,
                                   atol=1e-9 * 10**(3 * d))
    tj = np.cumsum(rng.uniform(0.8e-3, 1.6e-3, 600))
    cubic = np.column_stack([1 - 2 * tj + 3 * tj**2 - 4 * tj**3])
    (v, d1, d2), h0 = local_fit(tj, cubic, 51, 3, (0, 1, 2))
    np.testing.assert_allclose(v, cubic, atol=1e-10)
    np.testing.assert_allclose(d1[:, 0], -2 + 6 * tj - 12 * tj**2, atol=1e-7)
    np.testing.assert_allclose(d2[:, 0], 6 - 24 * tj, atol=1e-4)
    assert np.all((h0 > 0) & (h0 < 1))


def test_libfranka_log_to_csv_as_written(tmp_path):
    """The header ``franka::logToCSV`` writes (libfranka's src/logging/robot_state_log.cpp):
    time in integer ms, ``state.q[i]`` .. and ``cmd.`` columns, separators with or without a
    space; a lost packet (a 3 ms step) is a gap."""
    t, q, qd, tau = _reference()
    t_ms = np.round(t * 1e3)
    t_ms[300:] += 2.0
    arr = lambda name: [f"{name}[{k}]" for k in range(3)]  # noqa: E731
    head = ["time", "success_rate", *arr("state.q"), *arr("state.q_d"), *arr("state.dq"),
            *arr("state.dq_d"), *arr("state.tau_J"), *arr("state.tau_ext_hat_filtered"),
            *arr("cmd.q_d"), *arr("cmd.tau_J_d")]
    cols = [t_ms, 0 * t + 1, q, q, qd, qd, tau, 0 * tau, q, 0 * tau]
    for sep in (",", ", "):
        p = tmp_path / "franka.csv"
        text = _table(head, cols).replace(",", sep)
        p.write_text(text.replace(".0,", ",").replace(".0\n", "\n"))
        log = load_torque_log(p)
        assert "libfranka" in log.conditioning.columns and "read as ms" in log.conditioning.clock
        assert "state.q[0]..state.q[2]" in log.conditioning.columns
        assert len(log.segments) == 2 and log.conditioning.gaps[0].seconds == pytest.approx(3e-3)
        np.testing.assert_allclose(log.tau, tau)
        np.testing.assert_allclose(log.qc, q)


def test_ur_rtde_record_py_space_separated(tmp_path):
    """UR's RTDE client ``record.py`` writes its CSV space-separated (its CSVWriter's
    default delimiter); semicolons and tabs are read too."""
    t, q, qd, tau = _reference()
    head = ["timestamp", *(f"actual_q_{k}" for k in range(3)),
            *(f"actual_qd_{k}" for k in range(3)), *(f"actual_current_{k}" for k in range(3)),
            "runtime_state"]
    for sep in (" ", ";", "\t"):
        p = tmp_path / "robot_data.csv"
        p.write_text(_table(head, [t + 20.0, q, qd, tau / 5.0, 0 * t + 2]).replace(",", sep))
        log = load_torque_log(p, torque_constant=[5.0] * 3)
        assert "UR RTDE" in log.conditioning.columns and log.torque_from == "current"
        np.testing.assert_allclose(log.tau, tau)
        np.testing.assert_allclose(log.t, t + 20.0)
    text = _table(head, [t, q, qd, tau, 0 * t]).replace(",", " ")
    p.write_text(text.replace("\n0.3", "\n0.3 7", 1))
    with pytest.raises(InputError, match=r"line \d+: 12 fields, but the header has 11"):
        load_torque_log(p, torque_constant=[5.0] * 3)


def test_kuka_sunrise_trace(tmp_path):
    """A Sunrise trace: a "%" header, whitespace-separated, ZeitInSec + ZeitInNanoSec, the
    axes' measured and commanded positions in degrees, 0-based; torques named as FRI does."""
    t, q, _, tau = _reference()
    sec = np.floor(t + 100.0)
    nsec = np.round((t + 100.0 - sec) * 1e9)
    robot = "LBR_iiwa_7_R800_1"
    head = ["ZeitInSec", "ZeitInNanoSec", *(f"axisQMsr_{robot}[{k}]" for k in range(3)),
            *(f"axisQCmdT1m_{robot}[{k}]" for k in range(3)),
            *(f"MeasuredTorque_{k + 1}" for k in range(3))]
    p = tmp_path / "trace.log"
    p.write_text("%" + _table(head, [sec, nsec, np.degrees(q), np.degrees(q), tau])
                 .replace(",", " "))
    log = load_torque_log(p)
    assert "KUKA" in log.conditioning.columns
    np.testing.assert_allclose(log.t, t, atol=1e-9)
    np.testing.assert_allclose(log.q, q, atol=1e-12)
    np.testing.assert_allclose(log.qc, q, atol=1e-12)


def test_kuka_fri_pyfri_collect_data(tmp_path):
    """lbr-stack/pyfri's ``collect_data`` CSV as its C++ writes it: ``index,time,
    record_time_nsec,tsec,tnsec,mp1..,ip1..,mt1..,et1..,dt``, every number through a default
    ``std::ostream`` (6 significant digits). Its ``time`` column is a sum of nominal steps
    that stalls at 6 digits (1000.00 s repeats for 10 rows): the FRI clock tsec + tnsec is the
    time read, jitter and all."""
    t, q, _, tau = _reference()
    rng = np.random.default_rng(4)
    clock = 1.7e9 + 1000.0 + t + rng.uniform(-5e-5, 5e-5, t.size)  # the controller's clock
    sec = np.floor(clock)
    nsec = np.round((clock - sec) * 1e9)
    g6 = lambda v: f"{float(v):.6g}"  # noqa: E731 (std::ostream's default)
    j = range(1, 4)
    head = ["index", "time", "record_time_nsec", "tsec", "tnsec", *(f"mp{k}" for k in j),
            *(f"ip{k}" for k in j), *(f"mt{k}" for k in j), *(f"et{k}" for k in j), "dt"]
    rows = [",".join([str(i), g6(1000.0 + t[i]), str(int(1.7e18) + i * 1000000),
                      str(int(sec[i])), str(int(nsec[i])), *map(g6, q[i]), *map(g6, q[i]),
                      *map(g6, tau[i]), *map(g6, 0 * tau[i]), "0.001"])
            for i in range(t.size)]
    p = tmp_path / "lbr_data.csv"
    p.write_text(",".join(head) + "\n" + "\n".join(rows) + "\n")
    log = load_torque_log(p)
    assert "KUKA FRI pyfri" in log.conditioning.columns
    assert "tsec" in log.conditioning.columns and "et1" in log.conditioning.columns  # not used
    assert log.n_samples == t.size and log.segments == ()  # no repeats, no gap: tsec + tnsec
    np.testing.assert_allclose(log.t - log.t[0], clock - clock[0], atol=1e-9)
    np.testing.assert_allclose(log.q, q, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(log.qc, q, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(log.tau, tau, rtol=1e-5, atol=1e-5)
