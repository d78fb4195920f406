"""``zrp excite`` is safe to play (issue 32 part 7; issue 35 findings 6 and 8): q0 and every
command sample within the position, velocity, acceleration and torque limits, degrees caught,
sizes bounded before anything is allocated, the conditions recorded in the file, and nothing
written when a check fails."""

from __future__ import annotations

import time

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics.command import (
    MAX_SAMPLES,
    ExciteOptions,
    excitation_command,
    read_command_conditions,
    write_excitation_command,
)
from zrp.gap.dynamics.excitation import MAX_HARMONICS, design_excitation
from zrp.gap.dynamics.fourier import Fourier, random_fourier
from zrp.gap.dynamics.limits import JointLimits, check_command_limits

UR10_Q0 = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]
FAST = {"candidates": 1, "iterations": 0, "rate_hz": 100.0}


@pytest.fixture(scope="module")
def ur10():
    from mjcf.arm import load_arm
    from tests.arms import SHIPPED_URDFS, erd_root

    rel, end = SHIPPED_URDFS["ur10"]
    path = erd_root() / rel
    return load_arm(path, end_link=end), path


@pytest.fixture(scope="module")
def puma():
    from mjcf.arm import resolve_arm

    return resolve_arm("puma")


def _limits(n=2, **kw):
    base = {"lower": np.full(n, -1.0), "upper": np.full(n, 1.0), "velocity": np.full(n, 1.0),
            "acceleration": np.full(n, 2.0), "torque": np.full(n, np.inf),
            "names": tuple(f"j{k + 1}" for k in range(n)), "revolute": np.ones(n, bool)}
    base.update(kw)
    return JointLimits(**base)


# --- the one check of a command against limits ------------------------------------------

def test_check_passes_a_command_within_its_limits():
    t = np.linspace(0, 2 * np.pi, 2001)
    q = np.column_stack([0.5 * np.sin(t), 0.9 * np.cos(t)])
    qd = np.column_stack([0.5 * np.cos(t), -0.9 * np.sin(t)])
    check_command_limits(q, _limits(), t=t, qd=qd, qdd=-q, tau=np.zeros_like(q))


@pytest.mark.parametrize(("case", "message"), [
    ("position", "joint 2 (j2) reaches 1.1 rad at sample 1"),
    ("velocity", "joint 1 (j1) moves at 1.5 rad/s"),
    ("velocity_steps", "joint 1 (j1) moves at (sample to sample)"),
    ("acceleration", "joint 2 (j2) accelerates at"),
    ("torque", "joint 1 (j1) needs a torque of 12 N m"),
    ("nan", "positions must be finite"),
])
def test_check_names_the_joint_and_value_beyond_a_limit(case, message):
    t = np.linspace(0, 1, 101)
    q = np.zeros((101, 2))
    kw = {}
    lim = _limits()
    if case == "position":
        q[:, 1] = 1.1
    elif case == "velocity":
        kw["qd"] = np.full((101, 2), 0.0)
        kw["qd"][50, 0] = 1.5
    elif case == "velocity_steps":  # only the written samples tell: 0 -> 0.5 rad in 10 ms
        q[60:, 0] = 0.5
    elif case == "acceleration":
        q[:, 1] = 0.1 * np.sin(5 * t)  # |qd| <= 0.5 rad/s, |qdd| up to 2.5 > 2 rad/s^2
    elif case == "torque":
        kw["tau"] = np.zeros((101, 2))
        kw["tau"][3, 0] = 12.0
        lim = _limits(torque=np.array([10.0, 10.0]))
    else:
        q[5, 0] = np.nan
    with pytest.raises(InputError, match=r"^command") as err:
        check_command_limits(q, lim, t=t, **kw)
    assert message in str(err.value)


@pytest.mark.parametrize(("kw", "message"), [
    ({"velocity": np.array([1.0, np.nan])}, "velocity limit: joint 2 is nan"),
    ({"acceleration": np.array([-1.0, 1.0])}, "acceleration limit of joint 1 (j1): -1"),
    ({"torque": np.array([0.0, 1.0])}, "torque limit of joint 1 (j1): 0"),
    ({"lower": np.array([0.5, -1.0]), "upper": np.array([0.0, 1.0])}, "lower 0.5 > upper 0"),
    ({"upper": np.array([np.nan, 1.0])}, "upper position limit"),
])
def test_limits_themselves_are_checked(kw, message):
    with pytest.raises(InputError) as err:
        _limits(**kw)
    assert message in str(err.value)


def test_fourier_peaks_bound_the_series_between_samples():
    f = random_fourier(np.zeros(3), 0.5, 1.0, 3.0, harmonics=20, seed=4)
    dense = f.evaluate(np.linspace(0, 1 / f.f0_hz, 200_001))
    for bound, values in zip(f.peaks(), (dense[0], dense[1], dense[2]), strict=True):
        assert np.all(np.abs(values).max(0) <= bound)
        assert np.all(bound <= 1.001 * np.abs(values).max(0))  # and not loose


# --- bounded sizes (issue 35 finding 8) ---------------------------------------------------

@pytest.mark.parametrize(("kw", "field"), [
    ({"harmonics": 10 ** 6}, "harmonics"),
    ({"harmonics": 1}, "harmonics"),
    ({"candidates": 10 ** 9}, "candidates"),
    ({"iterations": 10 ** 9}, "iterations"),
    ({"f0_hz": float("nan")}, "f0_hz"),
])
def test_design_sizes_are_bounded_before_any_work(puma, kw, field):
    start = time.perf_counter()
    with pytest.raises(InputError, match=f"^{field}"):
        design_excitation(puma, np.zeros(6), 0.5, 1.0, 3.0, **kw)
    assert time.perf_counter() - start < 1.0  # refused up front, not after allocating
    assert MAX_HARMONICS == 50


@pytest.mark.parametrize(("kw", "message"), [
    ({"period_s": 3600.0, "rate_hz": 100000.0}, f"at most {MAX_SAMPLES:,}"),
    ({"period_s": 10.0, "rate_hz": 1.0, "harmonics": 5}, "below 20 samples a cycle"),
    ({"period_s": 10.0, "rate_hz": 333.33}, "samples, not a whole number"),
    ({"amplitude": 0.0}, "amplitude: joint 1 is 0"),
    ({"amplitude": [0.5, 0.5, -0.1, 0.5, 0.5, 0.5]}, "amplitude: joint 3 is -0.1"),
    ({"max_velocity": float("inf")}, "max_velocity: joint 1 is inf"),
    ({"max_acceleration": float("nan")}, "max_acceleration: joint 1 is nan"),
    ({"max_torque": [10.0, 10.0]}, "max_torque: expected 1 or 6 values"),
    ({"harmonics": 10 ** 6}, "harmonics"),
])
def test_options_are_refused_by_name_before_the_design(puma, tmp_path, kw, message):
    opts = {"q0": [0.0] * 6, **FAST, **kw}
    start = time.perf_counter()
    with pytest.raises(InputError) as err:
        excitation_command(puma, ExciteOptions(**opts))
    assert message in str(err.value)
    assert time.perf_counter() - start < 1.0


# --- q0 and the envelope inside the position limits; degrees caught ------------------------

def test_q0_outside_the_limits_is_refused_naming_joint_value_and_limits(ur10):
    arm, _ = ur10
    with pytest.raises(InputError) as err:
        excitation_command(arm, ExciteOptions(q0=[100, 0, 0, 0, 0, 0], **FAST))
    msg = str(err.value)
    assert "joint 1 (shoulder_pan_joint) is 100 rad" in msg
    assert "[-6.28319, 6.28319] rad" in msg
    assert "did you type degrees? use deg=True" in msg


def test_q0_in_degrees_is_caught_and_deg_reads_it(ur10, tmp_path):
    arm, _ = ur10
    deg = [0.0, -70.0, 70.0, -85.0, -85.0, 0.0]  # joint 2: -70 rad is beyond -2 pi
    with pytest.raises(InputError, match=r"joint 2 .*did you type degrees"):
        excitation_command(arm, ExciteOptions(q0=deg, **FAST))
    cmd = excitation_command(arm, ExciteOptions(q0=deg, amplitude=20.0, deg=True, **FAST))
    np.testing.assert_allclose(cmd.q[0], np.radians(deg), atol=1e-12)
    assert np.all(np.abs(cmd.q - np.radians(deg)).max(0) <= np.radians(20.0) + 1e-12)


def test_the_envelope_q0_plus_amplitude_must_fit(ur10):
    arm, _ = ur10
    q0 = [0.0, -1.2, 3.0, -1.5, -1.5, 0.0]  # joint 3's limits are +-pi
    with pytest.raises(InputError) as err:
        excitation_command(arm, ExciteOptions(q0=q0, amplitude=0.5, **FAST))
    msg = str(err.value)
    assert "joint 3 (elbow_joint)" in msg and "3.14159" in msg and "at most 0.141593" in msg


# --- the arm's own velocity and torque limits -----------------------------------------------

def test_a_velocity_above_the_arms_own_limit_is_refused(ur10):
    arm, _ = ur10
    np.testing.assert_allclose(arm.velocity_limits(), [2.16, 2.16, 3.15, 3.2, 3.2, 3.2])
    with pytest.raises(InputError, match=r"max_velocity: joint 1 \(shoulder_pan_joint\) 3 "
                                         r"rad/s is above the model's own limit 2.16"):
        excitation_command(arm, ExciteOptions(q0=UR10_Q0, max_velocity=3.0, **FAST))


def test_a_torque_above_the_models_own_limit_is_refused(ur10):
    arm, _ = ur10
    with pytest.raises(InputError, match=r"max_torque: joint 4 \(wrist_1_joint\) 100 N m is "
                                         r"above the model's own limit 54"):
        excitation_command(arm, ExciteOptions(q0=UR10_Q0, max_torque=100.0, **FAST))


def test_a_torque_limit_gravity_alone_breaks_writes_nothing(ur10, tmp_path):
    arm, _ = ur10
    with pytest.raises(InputError, match="torque"):
        excitation_command(arm, ExciteOptions(q0=UR10_Q0, max_torque=1.0, **FAST))


# --- the command as written -----------------------------------------------------------------

def test_every_written_sample_is_within_every_limit_and_the_file_says_so(ur10, tmp_path):
    arm, path = ur10
    opts = ExciteOptions(q0=UR10_Q0, amplitude=0.4, max_velocity=0.8, max_acceleration=2.0,
                         max_torque=[300, 300, 140, 50, 50, 50], candidates=2, iterations=2,
                         rate_hz=200.0)
    cmd = excitation_command(arm, opts)
    out = write_excitation_command(cmd, tmp_path / "cmd.csv", model=path)
    text = out.read_text()
    lines = text.splitlines()
    header = next(ln for ln in lines if not ln.startswith("#"))
    assert header.split(",")[:2] == ["t [s]", "qc1 [rad]"] and len(header.split(",")) == 7
    n_comments = sum(ln.startswith("#") for ln in lines)
    data = np.loadtxt(out, delimiter=",", skiprows=n_comments + 1)
    assert data.shape == (2000, 7)
    np.testing.assert_array_equal(data[:, 1:], cmd.q)  # written exactly as checked
    t, q = data[:, 0], data[:, 1:]
    lo, hi = arm.position_limits()
    assert np.all(q >= lo) and np.all(q <= hi)
    assert np.all(np.abs(q - UR10_Q0) <= 0.4)
    v = np.diff(q, axis=0) / np.diff(t)[:, None]
    assert np.abs(v).max() <= 0.8
    _, qd, qdd = cmd.excitation.command.evaluate(t)
    assert np.abs(qd).max() <= 0.8 and np.abs(qdd).max() <= 2.0
    tau = arm.inverse_dynamics(q, qd, qdd)  # independent of the design's own numbers
    assert np.all(np.abs(tau).max(0) <= [300, 300, 140, 50, 50, 50])
    cond = read_command_conditions(out)
    assert cond["model"].startswith(path.name) and "sha256" in cond["model"]
    for key in ("zrp", "joints", "units", "q0 [rad]", "period [s]", "rate [Hz]",
                "position limits [rad]", "velocity limits [rad/s]",
                "acceleration limits [rad/s^2]", "torque limits [N m]"):
        assert key in cond, key
    assert "0.8" in cond["velocity limits [rad/s]"] and "300" in cond["torque limits [N m]"]


def test_nothing_replaced_and_the_model_is_never_the_output(ur10, tmp_path):
    arm, path = ur10
    cmd = excitation_command(arm, ExciteOptions(q0=UR10_Q0, **FAST))
    out = write_excitation_command(cmd, tmp_path / "cmd.csv", model=path)
    with pytest.raises(Exception, match=r"exist|force"):
        write_excitation_command(cmd, out, model=path)
    copy = tmp_path / "ur10.urdf"
    copy.write_bytes(path.read_bytes())
    with pytest.raises(InputError, match="is the model"):
        write_excitation_command(cmd, copy, model=copy, overwrite=True)
    assert copy.read_bytes() == path.read_bytes()


def test_a_tampered_command_is_refused_before_writing(ur10, tmp_path):
    arm, path = ur10
    cmd = excitation_command(arm, ExciteOptions(q0=UR10_Q0, **FAST))
    q = cmd.q.copy()
    q[7, 2] = 3.2  # beyond elbow_joint's +-pi
    bad = type(cmd)(**{**cmd.__dict__, "q": q})
    out = tmp_path / "bad.csv"
    with pytest.raises(InputError, match=r"joint 3 .* reaches 3\.2 rad"):
        write_excitation_command(bad, out, model=path)
    assert not out.exists()


def test_design_refuses_an_envelope_beyond_the_limits_through_the_api(ur10):
    arm, _ = ur10
    with pytest.raises(InputError, match="joint 3 would move"):
        design_excitation(arm, np.array([0, 0, 3.0, 0, 0, 0]), 0.5, 1.0, 3.0,
                          candidates=1, iterations=0)


def test_fourier_evaluates_in_bounded_chunks():
    f = Fourier(np.zeros(2), np.ones((2, 3)), np.ones((2, 3)), 0.5)
    t = np.linspace(0, 2, 70_001)
    q, _, _ = f.evaluate(t)
    q2, _, _ = f._at(t)
    np.testing.assert_allclose(q, q2, rtol=0, atol=1e-12)


def test_a_joint_without_limits_still_refuses_more_than_a_turn(puma):
    """The built-in PUMA has no joint limits: 45 rad on a hinge cannot be a posture."""
    assert np.all(np.isinf(puma.position_limits()[1]))
    with pytest.raises(InputError) as err:
        excitation_command(puma, ExciteOptions(q0=[45, 0, 0, 0, 0, 0], **FAST))
    msg = str(err.value)
    assert "joint 1 (q1) is 45 rad, beyond one turn" in msg and "did you type degrees" in msg
    cmd = excitation_command(puma, ExciteOptions(q0=[45, 0, 0, 0, 0, 0], deg=True, **FAST))
    np.testing.assert_allclose(cmd.q0, np.radians([45, 0, 0, 0, 0, 0]))
    assert cmd.sources["torque"] == "none known" and np.all(np.isinf(cmd.limits.torque))
