"""The motion diagnosis (zrp.gap.motion): kernels and Jacobians against finite differences and
an ODE solver, the split by time segments, the CSV, and telling a 2 ms sync delay from a
5 ms servo lag (alike at constant speed, different under acceleration)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import zrp
from tests.measured import tracked_tool_point
from zrp.errors import InputError
from zrp.gap.model.problem import Problem
from zrp.gap.motion import Trajectory, diagnose_motion, load_trajectory, write_trajectory
from zrp.gap.motion.effects import MotionContext, effect_columns, linearise
from zrp.gap.motion.kernels import first_order_lag, play
from zrp.gap.motion.paths import exercise_moves
from zrp.gap.motion.segments import phases, split_segments, stream_noise_sigma

SIGMA = 0.02  # mm per coordinate


@pytest.fixture(scope="module")
def moves():
    return exercise_moves(np.radians([0, -20, 30, 0, 60, 0]), np.random.default_rng(1),
                          moves=8)


def _lagged(moves, t, tau):
    """First-order servo response by an adaptive ODE solver on the analytic command."""
    sol = solve_ivp(lambda tt, y: (moves(tt) - y) / tau, (t[0], t[-1]), moves(t[0]),
                    t_eval=t, rtol=1e-10, atol=1e-12, max_step=2e-3)
    return sol.y.T


# ---- kernels ---------------------------------------------------------------------------------
def test_lag_kernel_matches_ode_and_its_derivative() -> None:
    t = np.sort(np.r_[0.0, np.random.default_rng(0).uniform(0, 2, 1500), 2.0])
    u = np.sin(3 * t) + 0.5 * t**2
    tau = 0.02
    y, dy = first_order_lag(t, u, tau)
    ref = solve_ivp(lambda tt, yy: (np.sin(3 * tt) + 0.5 * tt**2 - yy) / tau, (0, 2), [u[0]],
                    t_eval=t, rtol=1e-11, atol=1e-13).y[0]
    # piecewise-linear input vs the exact one: h^2 u'' / 8 <= 1e-4 for gaps up to 10 ms
    assert np.max(np.abs(y - ref)) < 1e-4
    h = 1e-7
    fd = (first_order_lag(t, u, tau + h)[0] - first_order_lag(t, u, tau - h)[0]) / (2 * h)
    np.testing.assert_allclose(dy, fd, rtol=1e-5, atol=1e-8)


def test_play_kernel_derivative_and_hysteresis() -> None:
    t = np.linspace(0, 4, 4001)
    u = np.sin(2 * np.pi * 0.5 * t)
    r = 0.05
    y, dy = play(u, r)
    assert np.max(np.abs(y - u)) <= r + 1e-12
    h = 1e-7
    fd = (play(u, r + h)[0] - play(u, r - h)[0]) / (2 * h)
    np.testing.assert_allclose(dy, fd, atol=1e-6)
    rising = np.gradient(u) > 0.01
    assert np.allclose((y - u)[rising & (t > 1.2)], -r)  # lags by r while moving up


def test_effect_and_problem_jacobians_match_finite_differences(puma, moves) -> None:
    rng = np.random.default_rng(2)
    t = np.arange(0, moves.duration, 5e-3)
    traj = Trajectory(t, moves(t), tracked_tool_point(puma, moves(t), rng), frame="base")
    tau = rng.normal(0, 20, traj.q.shape)
    vals = {"sync.delay": 0.003, "q2.lag": 0.004, "q3.friction": 2e-4,
            "q2.dyn_compliance": 1e-5}
    for effect in ("sync_delay", "servo_lag", "reversal_friction", "dynamic_compliance"):
        for col in effect_columns(traj, effect, vals, tau):
            if col.name not in vals:
                continue
            h = 1e-6 * max(abs(col.value), 1e-3)
            up = {**vals, col.name: col.value + h}
            dn = {**vals, col.name: col.value - h}
            cu = next(c for c in effect_columns(traj, effect, up, tau) if c.name == col.name)
            cd = next(c for c in effect_columns(traj, effect, dn, tau) if c.name == col.name)
            fd = (cu.d - cd.d) / (2 * h)
            scale = np.abs(col.D).max()
            assert np.max(np.abs(fd - col.D)) <= 1e-4 * scale, col.name
    # the linearised specs in the static Problem: Jacobian column vs a finite difference of
    # the exact model (re-evaluated effect columns)
    cols = effect_columns(traj, "servo_lag", {"q2.lag": 0.004}, None)
    shift, specs = linearise(cols)
    ctx = MotionContext(puma, traj.measurements, shift=shift)
    theta = np.array([c.value for c in cols])
    prob = Problem(ctx, specs, np.arange(traj.n_samples))
    _, J = prob.residual_and_jacobian(theta)
    i = [s.name for s in specs].index("q2.lag")
    h = 1e-7

    def exact(v: float) -> np.ndarray:
        cc = effect_columns(traj, "servo_lag", {"q2.lag": v}, None)
        sh, sp = linearise(cc)
        return Problem(MotionContext(puma, traj.measurements, shift=sh), sp,
                       np.arange(traj.n_samples)).residual(np.array([c.value for c in cc]))
    fd = (exact(0.004 + h) - exact(0.004 - h)) / (2 * h)
    np.testing.assert_allclose(J[:, i], fd, rtol=1e-4, atol=1e-4 * np.abs(fd).max())


# ---- split, phases, noise ----------------------------------------------------------------------
def test_time_segments_are_contiguous_and_disjoint(puma, moves) -> None:
    t = np.arange(0, moves.duration, 2e-3)
    traj = Trajectory(t, moves(t), tracked_tool_point(puma, moves(t), np.random.default_rng(3)))
    sp = split_segments(traj, np.random.default_rng(0), 20, 0.25, 5)
    assert len(sp.withheld_segments) == 5
    assert np.intersect1d(sp.fitting, sp.withheld).size == 0
    assert np.array_equal(np.sort(np.concatenate(sp.folds)), sp.fitting)
    for f in sp.folds:  # whole segments per fold
        segs = np.unique(sp.segment[f])
        assert np.isin(np.flatnonzero(np.isin(sp.segment, segs)), f).all()
    ph = phases(traj).masks
    assert ph["high_speed"].any() and ph["after_stop"].any() and ph["reversal"].any()
    sigma, _ = stream_noise_sigma(traj)
    assert sigma == pytest.approx(SIGMA, rel=0.1)


# ---- delay vs lag ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def delay_and_lag(puma, moves):
    t = np.arange(0, moves.duration, 1e-3)
    q = moves(t)
    q_delay = moves(t - 0.002)
    q_lag = _lagged(moves, t, 0.005)
    rng = np.random.default_rng(4)
    return t, q, q_delay, q_lag, rng


def test_delay_and_lag_look_alike_at_constant_speed_differ_under_acceleration(
        moves, delay_and_lag) -> None:
    t, q, q_delay, q_lag, _ = delay_and_lag
    v, a = moves(t, 1), moves(t, 2)
    dev_d, dev_l = (q_delay - q)[:, 1], (q_lag - q)[:, 1]
    vmax, amax = np.abs(v[:, 1]).max(), np.abs(a[:, 1]).max()
    cruise = (np.abs(v[:, 1]) > 0.5 * vmax) & (np.abs(a[:, 1]) < 0.05 * amax)
    accel = np.abs(a[:, 1]) > 0.6 * amax
    # at constant speed both are -delay x velocity: the lag looks like a 5/2 longer delay
    ratio = dev_l[cruise] / dev_d[cruise]
    assert np.median(ratio) == pytest.approx(2.5, rel=0.03)
    # under acceleration the ratio moves away from 2.5 (tau^2 q'' against delta^2/2 q'')
    def mismatch(sel: np.ndarray) -> float:
        return float(np.sqrt(np.mean((dev_l[sel] - 2.5 * dev_d[sel]) ** 2)))
    assert mismatch(accel) > 5 * mismatch(cruise)
    # 1e-4 rad is 0.04 mm on a 0.4 m lever, twice the tracker noise: visible
    assert mismatch(accel) > 1e-4


@pytest.mark.slow
@pytest.mark.parametrize("case", ["delay", "lag"])
def test_sync_delay_told_apart_from_servo_lag(puma, delay_and_lag, case) -> None:
    t, q, q_delay, q_lag, _rng = delay_and_lag
    qa = q_delay if case == "delay" else q_lag
    traj = Trajectory(t, q, tracked_tool_point(puma, qa, np.random.default_rng(5 if case == "delay"
                                                                     else 6)))
    d = diagnose_motion(puma, traj, seed=0)
    noise = np.sqrt(3) * SIGMA
    assert d.final.rms <= 1.2 * noise
    if case == "delay":
        assert d.effects == ("sync_delay",)
        (p,) = d.parameters
        assert abs(p.value - 0.002) < 4 * p.stderr + 2e-6
    else:
        assert d.effects == ("servo_lag",)
        assert {p.joint for p in d.parameters} == set(range(1, 7))
        for p in d.parameters:
            assert abs(p.value - 0.005) < 4 * p.stderr + 2e-5, p.name
    ranked = {c["effect"]: c["cv_rms"] for c in d.steps[0].candidates}
    other = "servo_lag" if case == "delay" else "sync_delay"
    assert ranked[other] > 1.01 * d.steps[0].cv_rms  # not a tie


def test_withheld_segments_do_not_leak_and_static_effects_work_on_motion_data(puma, moves
                                                                              ) -> None:
    t = np.arange(0, moves.duration, 4e-3)
    q = moves(t)
    qa = q + np.array([0, 8e-4, 0, 0, 0, 0])  # a joint-2 offset (static)
    xyz = tracked_tool_point(puma, qa, np.random.default_rng(7))
    traj = Trajectory(t, q, xyz)
    effects = ("sync_delay", "servo_lag", "joint_offset")
    d1 = diagnose_motion(puma, traj, seed=3, effects=effects)
    assert d1.effects == ("joint_offset",) and d1.steps[0].joints == (2,)
    sp = split_segments(traj, np.random.default_rng(3))
    bad = np.array(xyz)
    bad[sp.withheld] += 5.0
    d2 = diagnose_motion(puma, Trajectory(t, q, bad), seed=3, effects=effects)
    assert [p.value for p in d2.parameters] == [p.value for p in d1.parameters]
    assert d2.final.rms > 5 * d1.final.rms


# ---- CSV -------------------------------------------------------------------------------------
def test_csv_round_trip_joint_time_stamps_and_errors(puma, moves, tmp_path) -> None:
    t = np.arange(0, 2.0, 1e-2)
    traj = Trajectory(t, moves(t), tracked_tool_point(puma, moves(t), np.random.default_rng(8)))
    path = write_trajectory(traj, tmp_path / "d.csv", deg=True, model=puma)
    back = load_trajectory(path, puma, deg=True)
    np.testing.assert_allclose(back.q, traj.q, rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(back.xyz, traj.xyz)
    with pytest.raises(zrp.OutputExistsError):
        write_trajectory(traj, path)
    # joints logged on the controller's clock (tq), 2.5 ms off the tracker's samples
    tq = t + 2.5e-3
    lines = ["t,q1,q2,q3,q4,q5,q6,x,y,z,tq"]
    for i in range(t.size):
        qq = moves(tq[i])
        lines.append(",".join(repr(float(v)) for v in [t[i], *qq, *traj.xyz[i, 0], tq[i]]))
    (tmp_path / "tq.csv").write_text("\n".join(lines) + "\n")
    got = load_trajectory(tmp_path / "tq.csv", puma)
    inner = (t > 0.1) & (t < 1.9)
    assert np.max(np.abs(got.q[inner] - moves(t[inner]))) < 1e-5
    text = (tmp_path / "d.csv").read_text().splitlines()
    text[5] = text[5].replace(text[5].split(",")[0], "0.0", 1)
    (tmp_path / "bad.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match=r"bad.csv line 6: t = 0.0 s is earlier"):
        load_trajectory(tmp_path / "bad.csv", puma, deg=True)
    (tmp_path / "nocol.csv").write_text("t,q1,x,y,z\n0,0,0,0,0\n")
    with pytest.raises(InputError, match="missing column"):
        load_trajectory(tmp_path / "nocol.csv", puma)
