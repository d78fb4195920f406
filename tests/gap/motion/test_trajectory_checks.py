"""The trajectory CSV's unit and rate checks (issue 26): the static loader's degree check in
its words, time stamps in ms or us named (or converted with time_unit), implausible rates
refused naming the range, streams and over-long lines refused, NaN named."""

from __future__ import annotations

import os

import numpy as np
import pytest

import zrp
from zrp.cli import main
from zrp.errors import InputError
from zrp.gap import load_measurements
from zrp.gap.motion import Trajectory, diagnose_motion, load_trajectory, write_trajectory

PUMA = zrp.load_model("puma")


def _traj(rate_hz: float = 200.0, samples: int = 80) -> Trajectory:
    t = np.arange(samples) / rate_hz
    q = np.radians([10, -20, 30, 5, 60, 0]) + 0.3 * np.sin(2.0 * t)[:, None]
    return Trajectory(t, q, zrp.forward_kinematics(PUMA, q).position, frame="base")


def _csv(tmp_path, traj: Trajectory, name: str = "d.csv", scale_t: float = 1.0,
         deg: bool = False):
    path = tmp_path / name
    out = Trajectory(traj.t * scale_t, traj.q, traj.xyz, traj.point_labels, traj.frame) \
        if scale_t != 1.0 else traj
    return write_trajectory(out, path, deg=deg, model=PUMA if deg else None)


def test_joints_in_degrees_are_named_in_the_static_loaders_words(tmp_path):
    path = _csv(tmp_path, _traj(), deg=True)
    with pytest.raises(InputError) as motion:
        load_trajectory(path, PUMA)
    assert "d.csv line 2: q1 is 10, beyond 6.283 rad" in str(motion.value)
    assert "(--deg on the command line)" in str(motion.value)
    # the static loader says the same about the same values (zrp.units.joint_values_to_rad;
    # only the remedy differs: a static CSV may also declare its column's unit)
    static = tmp_path / "static.csv"
    static.write_text("pose,q1,q2,q3,q4,q5,q6,x,y,z\nP1,10,-20,30,5,60,0,1,2,3\n")
    with pytest.raises(InputError) as stat:
        load_measurements(static, PUMA)
    same = "q1 is 10, beyond 6.283 rad (one turn, or the joint's limit): it cannot be an angle " \
           "in rad and looks like degrees"
    assert same in str(motion.value) and same in str(stat.value)
    np.testing.assert_allclose(load_trajectory(path, PUMA, deg=True).q, _traj().q, atol=1e-12)


def test_time_stamps_in_ms_are_refused_or_converted(tmp_path):
    traj = _traj(rate_hz=1000.0)
    path = _csv(tmp_path, traj, scale_t=1e3)  # 1 kHz stamped in ms: reads as 1 Hz
    with pytest.raises(InputError, match=r"d.csv line 2: column t has a median sample "
                                         r"interval of 1 s \(1 Hz\); a tracker stream is 5 Hz "
                                         r"to 100000 Hz: are the time stamps in ms"):
        load_trajectory(path, PUMA)
    got = load_trajectory(path, PUMA, time_unit="ms")
    np.testing.assert_allclose(got.t, traj.t, rtol=1e-12, atol=1e-15)
    assert got.rate_hz == pytest.approx(1000.0)
    with pytest.raises(InputError, match="time_unit: 'h' is not a time unit"):
        load_trajectory(path, PUMA, time_unit="h")


@pytest.mark.parametrize(("rate", "shown"), [(1e7, r"1e\+07 Hz"), (1e-4, r"0\.0001 Hz")])
def test_implausible_rates_name_the_range(tmp_path, rate, shown):
    path = _csv(tmp_path, _traj(rate_hz=rate))
    with pytest.raises(InputError, match=rf"\({shown}\); a tracker stream is 5 Hz to 100000 Hz"):
        load_trajectory(path, PUMA)
    # the API's boundary checks it too
    with pytest.raises(InputError, match="a tracker stream is 5 Hz to 100000 Hz"):
        diagnose_motion(PUMA, _traj(rate_hz=rate))


def test_cli_names_the_unit_option(tmp_path, capsys):
    path = _csv(tmp_path, _traj(rate_hz=1000.0), scale_t=1e3)
    code = main(["diagnose-motion", "--model", "puma", "--data", str(path),
                 "--out", str(tmp_path / "out")])
    assert code != 0
    err = capsys.readouterr().err
    assert "--time-unit ms" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_nan_and_non_numbers_are_named(tmp_path):
    path = _csv(tmp_path, _traj())
    lines = path.read_text().splitlines()
    cells = lines[4].split(",")
    for bad, msg in (("nan", "column q1 is nan; expected a finite number"),
                     ("abc", "column q1 is 'abc'; expected a number")):
        cells[2] = bad
        lines[4] = ",".join(cells)
        path.write_text("\n".join(lines) + "\n")
        with pytest.raises(InputError, match=rf"d.csv line 5: {msg}"):
            load_trajectory(path, PUMA)


def test_streams_long_lines_and_row_limits_are_refused(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="FIFO"):
        load_trajectory(fifo, PUMA)
    long = tmp_path / "long.csv"
    with open(long, "w") as fh:
        fh.write("t,q1,q2,q3,q4,q5,q6,x,y,z\n" + "1" * (3 * 2**20))
    with pytest.raises(InputError, match=r"long\.csv, line 2: longer than 1,048,576 characters"):
        load_trajectory(long, PUMA)
    path = _csv(tmp_path, _traj())
    with pytest.raises(InputError, match="line 12: more than max_rows=10 data rows"):
        load_trajectory(path, PUMA, max_rows=10)


def test_several_points_are_grouped_and_checked(tmp_path):
    traj = _traj()
    xyz = np.concatenate([traj.xyz, traj.xyz + 1.0], axis=1)  # (S, 2, 3)
    two = Trajectory(traj.t, traj.q, xyz, ("a", "b"), "base")
    path = write_trajectory(two, tmp_path / "two.csv")
    back = load_trajectory(path, PUMA)
    assert back.point_labels == ("a", "b")
    np.testing.assert_array_equal(back.xyz, two.xyz)
    text = path.read_text().replace(",b,", ",a,", 1)
    (tmp_path / "rep.csv").write_text(text)
    with pytest.raises(InputError, match="repeats a point label"):
        load_trajectory(tmp_path / "rep.csv", PUMA)
