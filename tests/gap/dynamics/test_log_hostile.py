"""Hostile input to the torque-log path (issue 35, finding 9): every case ends in a named
:class:`~zrp.errors.InputError` (file, line, column), never a traceback, NaN or a clamp."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics import TorqueLog, load_torque_log
from zrp.gap.dynamics.logfile import MAX_LINE

HEAD = "t [s],q1 [rad],q2 [rad],tau1 [Nm],tau2 [Nm]"


def _rows(n=200, step=1e-3):
    t = np.arange(n) * step
    return [[float(x), math.sin(x), math.cos(x), 2 * math.sin(3 * x), math.cos(5 * x)]
            for x in t]


def _text(head=HEAD, rows=None):
    rows = _rows() if rows is None else rows
    return head + "\n" + "\n".join(",".join(repr(v) for v in r) for r in rows) + "\n"


def _load(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_torque_log(path, **kw)


def _edit(rows, i, j, v):
    rows = [list(r) for r in rows]
    rows[i][j] = v
    return rows


CASES = {
    "header cell over the csv field limit":
        (("t," + "q" * 131_073 + ",tau1\n0,0,0\n").encode(),
         r"line 1: not a CSV header .*field limit"),
    "a header cell of 2,000 characters":
        (("t,q1,tau1," + "x" * 2000 + "\n0,0,0,0\n").encode(), r"line 1: column 4's name"),
    "seconds under t [ms]":
        (_text(HEAD.replace("t [s]", "t [ms]")).encode(), r"t \[ms\].*look like s"),
    "milliseconds under t [s]":
        (_text(rows=[[r[0] * 1e3, *r[1:]] for r in _rows()]).encode(), r"look like ms"),
    "degrees under [rad]":
        (_text(rows=[[r[0], 90 * r[1], r[2], *r[3:]] for r in _rows()]).encode(),
         r"column q1 is .* rad, outside .*look like degrees"),
    "a torque of 1e308":
        (_text(rows=_edit(_rows(), 50, 3, 1e308)).encode(), r"line 52: column tau1 is 1e\+308"),
    "a torque of inf":
        (_text(rows=_edit(_rows(), 50, 4, math.inf)).encode(),
         r"line 52: column tau2 \[Nm\] is 'inf'; expected a finite"),
    "q of 1e6 rad":
        (_text(rows=_edit(_rows(), 7, 2, 1e6)).encode(), r"line 9: column q2 is 1e\+06"),
    "a 1e30 kg payload":
        (_text(HEAD + ",payload [kg]", [[*r, 1e30 if k == 3 else 0.0]
                                         for k, r in enumerate(_rows())]).encode(),
         r"line 5: column payload is 1e\+30 kg"),
    "a time step of 1e-12 s": (_text(rows=_rows(step=1e-12)).encode(), r"implausible"),
    "non-UTF-8 bytes":
        (_text().encode().replace(b"\n0.002", b"\n\xff0.002", 1), r"line 4: not UTF-8"),
    "a NUL byte":
        (_text().encode().replace(b"\n0.002", b"\n0.0\x0002", 1), r"line 4: column t"),
    "no data rows": (HEAD.encode() + b"\n", r"0 data row"),
    "one data row": (_text(rows=_rows(1)).encode(), r"1 data row"),
    "an empty file": (b"", r"empty file"),
    "a line over the bound":
        ((_text() + "1," * (MAX_LINE // 2 + 10) + "\n").encode(), r"line 202: longer than"),
    "a row of the wrong width": (_text().replace("\n0.003", "\n9,0.003", 1).encode(),
                                 r"line 5: 6 fields, but the header has 5"),
    "time going backwards": (_text(rows=_edit(_rows(), 9, 0, 0.001)).encode(),
                             r"line 11: column t is 0.001 s, earlier"),
    "a header of no known form": (b"a,b,c\n1,2,3\n4,5,6\n", r"accepted: zrp"),
    "a quote that never closes":
        (_text().replace("\n0.003", '\n"0.003', 1).encode(), r"line 5"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_file_is_a_named_error(tmp_path, case):
    data, match = CASES[case]
    p = tmp_path / "log.csv"
    p.write_bytes(data)
    with pytest.raises(InputError, match=match):
        _load(p)


def test_whitespace_lines_and_crlf_are_skipped_and_counted(tmp_path):
    text = _text().replace("\n0.003", "\n   \t \n\n# a comment\n0.003", 1).replace("\n", "\r\n")
    p = tmp_path / "ws.csv"
    p.write_bytes(text.encode())
    log = _load(p)
    assert log.n_samples == 200 and log.conditioning.skipped_lines == 3
    assert log.lines[3] == 8  # the file line, after the three skipped


def test_a_repeated_stamp_with_other_values_keeps_the_first_and_says_so(tmp_path):
    rows = _rows()
    rows.insert(11, [rows[10][0], 9.0, 9.0, 9.0, 9.0])
    p = tmp_path / "rep.csv"
    p.write_text(_text(rows=rows))
    log = _load(p)
    assert log.n_samples == 200 and log.conditioning.conflicts == 1
    assert log.conditioning.conflict_lines == (13,)
    assert np.all(log.q < 2.0)


@pytest.mark.parametrize(("kw", "match"), [
    ({"q": np.zeros((5, 2))}, r"TorqueLog.q: shape \(5, 2\)"),
    ({"tau": np.zeros((10, 3))}, r"TorqueLog.tau: shape \(10, 3\), but q is \(10, 2\)"),
    ({"t": np.zeros((10, 1))}, r"TorqueLog.t: 2-dimensional"),
    ({"t": np.r_[np.arange(9), 3.0]}, r"row 9: t does not increase"),
    ({"t": np.array(["a"] * 10)}, r"TorqueLog.t: not an array of numbers"),
    ({"q": np.full((10, 2), np.nan)}, r"column q1 is nan"),
    ({"payload": np.full(10, 1e30)}, r"column payload is 1e\+30 kg"),
    ({"payload": np.ones(4)}, r"TorqueLog.payload: 4 values for 10 samples"),
    ({"segments": ((0, 4), (5, 10))}, r"TorqueLog.segments"),
    ({"segments": ((0, "x"),)}, r"TorqueLog.segments"),
    ({"unmeasured": {5: "x"}}, r"TorqueLog.unmeasured"),
    ({"t": np.zeros(1), "q": np.zeros((1, 2)), "tau": np.zeros((1, 2))}, r"1 sample"),
    ({"qd": np.zeros(10)}, r"TorqueLog.qd: 1-dimensional"),
    ({"tau": None}, r"TorqueLog.tau: required"),
])
def test_torquelog_from_the_api_checks_its_arrays(kw, match):
    base = {"t": np.arange(10) * 1e-3, "q": np.zeros((10, 2)), "qd": None,
            "tau": np.ones((10, 2))}
    base.update(kw)
    with pytest.raises(InputError, match=match):
        TorqueLog(**base)
