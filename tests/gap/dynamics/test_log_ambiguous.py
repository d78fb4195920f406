"""Issue 41 findings 6, 7 and 9 at reading: a clock unit that is not one (``t [h]``,
``t [N]``), two complete column forms or two clocks in one header, and a Sunrise nanoseconds
column written as the whole time: each a named error, or read the one documented way and
said."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics import load_torque_log

N = 300


def _t():
    return np.arange(N) * 1e-3


def _write(tmp_path, head, cols, name="log.csv"):
    table = np.column_stack(cols)
    p = tmp_path / name
    p.write_text(",".join(head) + "\n" + "\n".join(",".join(repr(float(v)) for v in r)
                                                   for r in table) + "\n")
    return p


def _load(p, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_torque_log(p, **kw)


def _q(t):
    return np.column_stack([np.sin(3 * t), np.cos(2 * t)])


def _tau(t):
    return np.column_stack([2 * np.sin(5 * t), np.cos(7 * t)])


@pytest.mark.parametrize("unit", ["h", "N", "kg", "min"])
def test_a_clock_unit_that_is_not_one_is_named(tmp_path, unit):
    t = _t()
    p = _write(tmp_path, [f"t [{unit}]", "q1 [rad]", "q2 [rad]", "tau1 [Nm]", "tau2 [Nm]"],
               [t, _q(t), _tau(t)])
    with pytest.raises(InputError, match=rf"column t \[{unit}\]: '{unit}' is not a clock unit; "
                                         r"declare one of s, ms, us, ns"):
        _load(p)


def test_two_complete_forms_are_refused_naming_both(tmp_path):
    t = _t()
    head = ["t [s]", "q1", "q2", "tau1", "tau2", "actual_q_0", "actual_q_1",
            "actual_current_as_torque_0", "actual_current_as_torque_1"]
    p = _write(tmp_path, head, [t, _q(t), _tau(t), _q(t) + 0.1, _tau(t) * 2])
    with pytest.raises(InputError, match=r"two complete column forms: .*actual_q_0\.\.actual_q_1"
                                         r".*keep one set of columns"):
        _load(p)


def test_two_clocks_are_refused_naming_both(tmp_path):
    t = _t()
    head = ["time [s]", "timestamp", "q_0", "q_1", "tau_J_0", "tau_J_1"]  # libfranka
    p = _write(tmp_path, head, [t, 2 * t + 5, _q(t), _tau(t)])
    with pytest.raises(InputError, match=r"two clocks: columns time and timestamp.*keep one time "
                                         r"column"):
        _load(p)


def test_a_ros_stamp_beside_the_receive_time_is_read_and_said(tmp_path):
    t = _t()
    head = ["%time", "field.header.stamp", "field.position0", "field.position1",
            "field.effort0", "field.effort1"]
    p = _write(tmp_path, head, [(t + 1.7e9 + 0.003) * 1e9, (t + 1.7e9) * 1e9, _q(t), _tau(t)])
    log = _load(p)
    assert "other clock column(s) %time not used (the sensor stamp field.header.stamp is)" \
        in log.conditioning.clock


def _sunrise(tmp_path, sec, nsec):
    head = ["ZeitInSec", "ZeitInNanoSec", "A1 [rad]", "A2 [rad]", "MeasuredTorque_1",
            "MeasuredTorque_2"]
    t = _t()
    table = np.column_stack([sec, nsec, _q(t), _tau(t)])
    p = tmp_path / "trace.csv"
    p.write_text(",".join(head) + "\n" + "\n".join(
        ",".join([str(int(r[0])), str(int(r[1])), *(repr(float(v)) for v in r[2:])])
        for r in table) + "\n")
    return p


def test_sunrise_nanoseconds_as_a_total_do_not_double_the_clock(tmp_path):
    t = _t() + 100.0
    sec = np.floor(t)
    p = _sunrise(tmp_path, sec, np.round(t * 1e9))  # the whole time in ns, not the fraction
    log = _load(p)
    np.testing.assert_allclose(log.t, t - t[0], atol=1e-9)
    assert "holds the whole time in ns" in log.conditioning.clock


def test_sunrise_nanoseconds_as_the_fraction_still_read(tmp_path):
    t = _t() + 100.0
    sec = np.floor(t)
    p = _sunrise(tmp_path, sec, np.round((t - sec) * 1e9))
    np.testing.assert_allclose(_load(p).t, t - t[0], atol=1e-9)


def test_sunrise_nanoseconds_that_agree_with_nothing_are_refused(tmp_path):
    t = _t() + 100.0
    p = _sunrise(tmp_path, np.floor(t), np.round(t * 1e9) + 5e10)
    with pytest.raises(InputError, match=r"column ZeitInNanoSec is .* beyond one second"):
        _load(p)


def test_negative_nanoseconds_are_refused(tmp_path):
    t = _t() + 100.0
    nsec = np.round((t - np.floor(t)) * 1e9)
    nsec[7] = -5
    with pytest.raises(InputError, match=r"column ZeitInNanoSec is -5 at data row 8"):
        _load(_sunrise(tmp_path, np.floor(t), nsec))
