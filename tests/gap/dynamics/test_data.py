"""The torque log reader: units, optional groups, named errors, and the zero-phase derivatives
against closed forms."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics import TorqueLog, derive_states, load_torque_log, write_torque_log


def _write(path, header, rows):
    path.write_text(header + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


def _sine_log(n=2, fs=1000.0, seconds=2.0):
    t = np.arange(int(fs * seconds)) / fs
    w = 2 * math.pi * np.array([0.7, 1.3])[:n]
    q = 0.5 * np.sin(w * t[:, None])
    return t, q, w


def test_round_trip_with_units(tmp_path):
    t, q, _ = _sine_log()
    log = TorqueLog(t, q, None, 3.0 * q, payload=np.full(t.size, 1.5))
    p = write_torque_log(log, tmp_path / "a.csv")
    back = load_torque_log(p)
    np.testing.assert_array_equal(back.q, q)
    np.testing.assert_array_equal(back.tau, 3.0 * q)
    assert back.qd is None and back.payload is not None and back.dt == pytest.approx(1e-3)
    with pytest.raises(Exception, match="exists"):
        write_torque_log(log, p)


def test_declared_units_convert(tmp_path):
    p = _write(tmp_path / "u.csv", "t [ms],q1 [deg],qd1 [deg/s],tau1 [mNm],payload [g]",
               [[0, 90, 180, 1500, 500], [10, 45, 0, 500, 500], [20, 0, 0, 0, 500]])
    log = load_torque_log(p)
    assert log.t[1] == pytest.approx(0.01)
    assert log.q[0, 0] == pytest.approx(math.pi / 2)
    assert log.qd[0, 0] == pytest.approx(math.pi)
    assert log.tau[0, 0] == pytest.approx(1.5)
    assert log.payload[0] == pytest.approx(0.5)


def test_header_units_are_zrp_units(tmp_path):
    """One header syntax with every CSV of ZRP (zrp.units.split_unit): ``q1[deg]`` as
    ``q1 [deg]``; a slide's position in any length unit of zrp.units."""
    p = _write(tmp_path / "v.csv", "t[ms],q1[deg],q2[cm],tau1[Nm],tau2[N]",
               [[0, 90, 5, 1, 1], [10, 45, 2, 2, 1], [20, 0, 0, 1, 2]])
    log = load_torque_log(p)
    assert log.t[1] == pytest.approx(0.01)
    np.testing.assert_allclose(log.q[0], [math.pi / 2, 0.05])
    with pytest.raises(InputError, match=r"line 1: 'q1\[deg' is not NAME or NAME\[UNIT\]"):
        load_torque_log(_write(tmp_path / "w.csv", "t,q1[deg,tau1", [[0, 0, 0]]))


def test_missing_units_warn(tmp_path):
    p = _write(tmp_path / "s.csv", "t,q1,tau1", [[0, 0, 0], [0.01, 1, 1], [0.02, 0, 0]])
    with pytest.warns(Warning, match="no unit declared for t, q1, tau1"):
        load_torque_log(p)


def test_currents_need_torque_constant(tmp_path):
    p = _write(tmp_path / "i.csv", "t [s],q1 [rad],q2 [rad],i1 [A],i2 [mA]",
               [[0, 0, 0, 1, 1000], [0.01, 1, 1, 2, 2000]])
    with pytest.raises(InputError, match="torque_constant"):
        load_torque_log(p)
    log = load_torque_log(p, torque_constant=[10.0, 5.0])
    np.testing.assert_allclose(log.tau, [[10, 5], [20, 10]])
    assert log.torque_from == "current"
    # a drive whose current counts the other way has a negative constant (issue 44)
    log = load_torque_log(p, torque_constant=[-8.7, 5.0])
    np.testing.assert_allclose(log.tau, [[-8.7, 5], [-17.4, 10]])
    with pytest.raises(InputError, match="zero for joint 2"):
        load_torque_log(p, torque_constant=[1.0, 0.0])
    with pytest.raises(InputError, match="2 finite"):
        load_torque_log(p, torque_constant=[1.0])


@pytest.mark.parametrize(("header", "rows", "match"), [
    ("t,q1,tau1,x", [[0, 0, 0, 0]], "unknown column 'x'"),
    ("t,q1,q2,tau1", [[0, 0, 0, 0]], "tau1..tau2 must all be given"),
    ("t,q1,qd1", [[0, 0, 0]], "no torques"),
    ("t,q1,tau1,tau1", [[0, 0, 0, 0]], "more than once"),
    ("t,q1 [furlong],tau1", [[0, 0, 0]], r"q1 has unit \[furlong\]"),
    ("t,q1,tau1", [[0, 0, 0]], "1 data row"),
    ("t,q1,tau1,q3", [[0, 0, 0, 0]], "missing column"),
    ("t,q1,tau1", [[0, 0, 0], [1, "x", 0]], "line 3: column q1 is 'x'"),
    ("t,q1,tau1", [[0, 0, 0], [1, 0, "nan"]], "line 3: column tau1 is 'nan'"),
    ("t,q1,tau1", [[0, 0, 0], [1, 0]], "line 3: 2 fields"),
    ("t,q1,tau1", [[0, 0, 0], [1, 0, 0], [0.5, 0, 0]], "line 4: column t"),
    ("t,q1,tau1,payload", [[0, 0, 0, 1], [0.01, 1, 1, -1]], "line 3: column payload"),
])
def test_named_errors(tmp_path, header, rows, match):
    p = _write(tmp_path / "bad.csv", header, rows)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError, match=match):
            load_torque_log(p)


def test_comment_lines_keep_line_numbers(tmp_path):
    p = _write(tmp_path / "c.csv", "t,q1,tau1", [["# note"], [0, 0, 0], [1, 1, 1], [2, 0, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = load_torque_log(p)
    assert log.lines.tolist() == [3, 4, 5]


def test_too_many_rows(tmp_path):
    p = _write(tmp_path / "m.csv", "t,q1,tau1", [[k, 0, 0] for k in range(5)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError, match="max_rows = 4"):
            load_torque_log(p, max_rows=4)


def test_derivatives_match_closed_form():
    t, q, w = _sine_log()
    rng = np.random.default_rng(0)
    log = TorqueLog(t, q + rng.normal(0, 1e-5, q.shape), None, np.zeros_like(q))
    s = derive_states(log, window_s=0.1)
    inner = slice(100, -100)
    qd = 0.5 * w * np.cos(w * t[:, None])
    qdd = -0.5 * w**2 * np.sin(w * t[:, None])
    assert np.max(np.abs(s.qd - qd)[inner]) < 0.01 * np.max(np.abs(qd))
    assert np.max(np.abs(s.qdd - qdd)[inner]) < 0.03 * np.max(np.abs(qdd))
    # zero phase: no lag of the acceleration against the closed form (the cross-correlation
    # peaks at 0 samples)
    a, b = s.qdd[inner, 0], qdd[inner, 0]
    lags = range(-20, 21)
    best = max(lags, key=lambda k: float(np.dot(np.roll(a, k), b)))
    assert best == 0


def test_window_too_short():
    t, q, _ = _sine_log(seconds=0.5, fs=50.0)
    with pytest.raises(InputError, match="window_s"):
        derive_states(TorqueLog(t, q, None, q), window_s=0.05)
