"""Seeded fuzz of the torque-log reader (issue 41): random mutations of a valid log CSV
(header names and units, numbers, NaN, huge values, repeated rows, truncated lines, frozen
stretches, second clocks and forms) give a log or a ZRPError, nothing else.

``ZRP_FUZZ41_CASES`` sets the number of cases (default 300); the documented long run:

    ZRP_FUZZ41_CASES=5000 python3 -m pytest -q tests/gap/dynamics/test_fuzz_log41.py
"""

from __future__ import annotations

import os
import warnings

import numpy as np

from zrp.errors import ZRPError
from zrp.gap.dynamics import load_torque_log

CASES = int(os.environ.get("ZRP_FUZZ41_CASES", "300"))
HEAD = ["t [s]", "q1 [rad]", "q2 [rad]", "tau1 [Nm]", "tau2 [Nm]"]
NAMES = ["t [h]", "t [N]", "t [ms]", "time", "timestamp", "%time", "field.header.stamp",
         "ZeitInSec", "ZeitInNanoSec", "tsec", "tnsec", "A1", "A2", "MeasuredTorque_1",
         "MeasuredTorque_2", "q_0", "tau_J_0", "actual_q_0", "actual_current_as_torque_0",
         "q1 [deg]", "tau1 [mNm]", "q1 [kg]", "tau2 [", "q3", "tau3", "payload [g]", "",
         "x" * 300, "q1 [rad] [rad]", "i1 [A]", "qc1"]
CELLS = ["nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "", " ", "abc", "0x10", "1e999",
         "--1", "1,2", "\x00", "0", "-0"]


def _base(rng: np.random.Generator) -> list[list[str]]:
    n = int(rng.integers(20, 400))
    t = np.cumsum(rng.uniform(0.5e-3, 1.5e-3, n))
    q = 0.5 * np.sin(np.outer(t, [3.0, 5.0]))
    tau = 2.0 * np.cos(np.outer(t, [3.0, 7.0])) + rng.normal(0, 0.01, q.shape)
    return [[repr(float(v)) for v in r] for r in np.column_stack([t, q, tau])]


def _rename(rng, head, rows):
    head[int(rng.integers(len(head)))] = str(rng.choice(NAMES))


def _cell(rng, head, rows):
    r = rows[int(rng.integers(len(rows)))]
    if r:
        r[int(rng.integers(len(r)))] = str(rng.choice(CELLS))


def _repeat(rng, head, rows):
    i = int(rng.integers(len(rows)))
    rows[i:i] = [list(rows[i]) for _ in range(int(rng.integers(1, 200)))]


def _truncate_line(rng, head, rows):
    i = int(rng.integers(len(rows)))
    rows[i] = rows[i][:int(rng.integers(0, len(rows[i]) + 1))]


def _freeze(rng, head, rows):
    a, c = int(rng.integers(len(rows))), int(rng.integers(1, 5))
    for r in rows[a:]:
        if len(r) > c and len(rows[a]) > c:
            r[c] = rows[a][c]


def _column(rng, head, rows):
    head.append(str(rng.choice(NAMES)))
    for r in rows:
        r.append(repr(float(rng.normal() * 10.0 ** float(rng.integers(-3, 12)))))


def _scale(rng, head, rows):
    k, f = int(rng.integers(len(head))), 10.0 ** float(rng.integers(-9, 10))
    for r in rows:
        try:
            r[k] = repr(float(r[k]) * f)
        except (ValueError, IndexError):
            pass


def _cut(rng, head, rows):
    del rows[int(rng.integers(0, len(rows) + 1)):]


def _shuffle(rng, head, rows):
    rng.shuffle(rows)


OPS = (_rename, _cell, _repeat, _truncate_line, _freeze, _column, _scale, _cut, _shuffle)


def _mutate(rng: np.random.Generator, head: list[str], rows: list[list[str]]) -> str:
    for _ in range(int(rng.integers(1, 5))):
        if rows and head:
            OPS[int(rng.integers(len(OPS)))](rng, head, rows)
    return ",".join(head) + "\n" + "\n".join(",".join(r) for r in rows) + "\n"


def test_mutated_logs_give_a_log_or_a_zrp_error(tmp_path):
    rng = np.random.default_rng(41)
    escapes = []
    p = tmp_path / "log.csv"
    for case in range(CASES):
        p.write_text(_mutate(rng, list(HEAD), _base(rng)), encoding="utf-8")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                load_torque_log(p)
            except ZRPError:
                pass
            except Exception as exc:
                escapes.append((case, type(exc).__name__, str(exc)[:200]))
    assert not escapes, escapes[:5]
