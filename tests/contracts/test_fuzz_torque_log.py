"""Fuzz test of the torque-log path (issue 35, finding 9): the reader
(:func:`zrp.gap.dynamics.load_torque_log`) on mutated logs of every controller form (jitter,
repeated rows and a gap included), on headers assembled from the column tables with nasty
names and cells, and on the Python API (:class:`zrp.gap.dynamics.TorqueLog` built from random
arrays); a log that loads is also taken through :func:`zrp.gap.dynamics.derive_states` and
the torque noise. As in test_fuzz_readers.py, the only assertion: a result, or an error of
the project's hierarchy (:class:`zrp.ZRPError`).

CI runs a seeded slice of ``ZRP_FUZZ_EXAMPLES`` cases per test (default 60). The documented
long run, 5,000 cases for each test:

    ZRP_FUZZ_EXAMPLES=5000 python3 -m pytest -q tests/contracts/test_fuzz_torque_log.py

Run on the final code (shared 2-core machine): 5,000 cases for each of the three fuzz tests
here, none escaped (hypothesis' statistics: 5,000 passing, 0 failing each; mutated logs 13 s,
assembled headers 26 s, the API 12 s; 0.48 GB peak). An earlier 5,000-case run, before the
real-time-axis filter was made faster, also found none (313 s).
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tests.contracts.test_fuzz_readers import NASTY, mutated
from zrp.errors import ZRPError
from zrp.gap.dynamics import TorqueLog, derive_states, load_torque_log
from zrp.gap.dynamics.diagnosis import torque_noise

EXAMPLES = int(os.environ.get("ZRP_FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])


def _rows(n: int = 80, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Jittered time stamps (s) with one 5 ms gap, positions and torques of 3 joints."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.8e-3, 1.6e-3, n))
    t[n // 2:] += 5e-3
    q = 0.4 * np.sin(np.outer(t, [3.0, 5.0, 7.0]))
    return t, q, 2.0 * np.cos(np.outer(t, [3.0, 5.0, 7.0])) + rng.normal(0, 0.01, q.shape)


def _csv(header: list[str], cols: list[np.ndarray], repeat: int = 7) -> str:
    table = np.column_stack(cols)
    lines = [",".join(header)]
    for i, row in enumerate(table):
        lines.append(",".join(repr(float(v)) for v in row))
        if i % repeat == 3:
            lines.append(lines[-1])
    return "\n".join(lines) + "\n"


T, Q, TAU = _rows()
J = range(3)
ZRP_TEXT = _csv(["t [s]", *(f"q{k + 1} [rad]" for k in J), *(f"tau{k + 1} [Nm]" for k in J),
                 "payload [kg]"], [T, Q, TAU, 0 * T + 0.5])
FRANKA_TEXT = _csv(["time", *(f"q_{k}" for k in J), *(f"dq[{k}]" for k in J),
                    *(f"tau_J{k}" for k in J), "O_T_EE_0"], [T * 1e3, Q, Q, TAU, T])
RTDE_TEXT = _csv(["timestamp", *(f"actual_q_{k}" for k in J),
                  *(f"actual_current_{k}" for k in J), *(f"target_q_{k}" for k in J)],
                 [T + 1.7e6, Q, TAU / 10, Q])
ROS_TEXT = _csv(["field.header.stamp", *(f"field.position{k}" for k in J),
                 *(f"field.effort{k}" for k in J)], [(T + 1.7e9) * 1e9, Q, TAU])
KUKA_TEXT = _csv(["ZeitInSec", *(f"A{k + 1}" for k in J), *(f"MeasuredTorque_{k + 1}" for k in J)],
                 [T, np.degrees(Q), TAU])
BASES = [ZRP_TEXT, FRANKA_TEXT, RTDE_TEXT, ROS_TEXT, KUKA_TEXT]

NAMES = ["t", "time", "timestamp", "%time", "field.header.stamp", "__time", "q1", "q2", "q0",
         "qd1", "tau1", "tau2", "i1", "qc1", "payload", "q_0", "q[1]", "dq_0", "tau_J_0",
         "q_d_0", "actual_q_0", "actual_qd_0", "actual_current_0", "target_q_0", "A1",
         "MeasuredJointPosition_1", "MeasuredTorque_A1", "field.position0", "field.effort0",
         "field.name0", "/joint_states/position/j", "/joint_states/effort/j", "position_j",
         "effort_j", "t [ms]", "t [ns]", "q1 [deg]", "tau1 [mNm]", "payload [g]", "q1 [rad]"]


@pytest.fixture(scope="module")
def tmp_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz_tlog")


def _through(path: Path, **kw: object) -> None:
    """Read ``path`` and, when it loads, derive its states and noise: only ZRPErrors."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            log = load_torque_log(path, **kw)  # type: ignore[arg-type]
            derive_states(log, window_s=0.02)
            torque_noise(log, 0.02)
        except ZRPError:
            pass


@FUZZ
@given(data=st.one_of(*(mutated(b) for b in BASES)),
       kt=st.one_of(st.none(), st.just([10.0, 10.0, 10.0]), st.just([1.0, -1.0])))
def test_mutated_logs(tmp_dir, data, kt):
    path = tmp_dir / "log.csv"
    path.write_bytes(data)
    _through(path, torque_constant=kt)


@st.composite
def assembled(draw: st.DrawFn) -> bytes:
    """A header of 1-9 names from the tables (or nasty ones) and 0-40 rows of cells that are
    mostly numbers of every size, sometimes nasty."""
    header = draw(st.lists(st.one_of(st.sampled_from(NAMES), st.sampled_from(NASTY)),
                           min_size=1, max_size=9))
    number = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                       st.integers(-10**6, 10**20).map(str), st.sampled_from(NASTY))
    rows = draw(st.lists(st.lists(number, min_size=len(header), max_size=len(header)),
                         max_size=40))
    step = draw(st.sampled_from([1e-12, 1e-3, 1.0, 1e6]))
    text = ",".join(header) + "\n" + "\n".join(
        ",".join([repr(k * step), *r[1:]]) for k, r in enumerate(rows)) + "\n"
    return text.encode("utf-8", errors="surrogatepass")


@FUZZ
@given(data=assembled())
def test_assembled_headers(tmp_dir, data):
    path = tmp_dir / "asm.csv"
    path.write_bytes(data)
    _through(path, torque_constant=[10.0] * 3)


finite = st.floats(-1e3, 1e3, allow_nan=False)
anything = st.floats(allow_nan=True, allow_infinity=True)


@FUZZ
@given(s=st.integers(0, 40), n=st.integers(0, 3), shift=st.integers(-2, 2),
       wild=st.booleans(), seg=st.sampled_from([(), ((0, 5),), ((0, 3), (3, 9))]),
       data=st.data())
def test_the_api(s, n, shift, wild, seg, data):
    elems = anything if wild else finite
    t = np.cumsum(data.draw(hnp.arrays(np.float64, s, elements=st.floats(-1e-3, 2e-3))))
    q = data.draw(hnp.arrays(np.float64, (s, n), elements=elems))
    tau = data.draw(hnp.arrays(np.float64, (max(0, s + shift), n), elements=elems))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            log = TorqueLog(t, q, None, tau, segments=seg)
            derive_states(log, window_s=0.005)
            torque_noise(log, 0.005)
        except ZRPError:
            pass


def test_the_unmutated_bases_load(tmp_dir):
    """The fuzzer's starting points are valid logs (else it tests only the first error)."""
    for k, text in enumerate(BASES):
        path = tmp_dir / f"base{k}.csv"
        path.write_text(text)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            log = load_torque_log(path, torque_constant=[10.0] * 3)
        assert log.n_joints == 3 and len(log.segments) == 2 and log.conditioning.repeats > 0
