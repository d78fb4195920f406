"""``zrp excite`` never writes a command outside a limit (issue 32 part 7, issue 35 findings
6, 8 and 12): the reproductions of the issues end in named errors and no file."""

from __future__ import annotations

import time

import numpy as np
import pytest

from zrp.cli import main

FAST = ["--candidates", "1", "--iterations", "0", "--rate", "100"]


@pytest.fixture(scope="module")
def ur10():
    from tests.arms import SHIPPED_URDFS, erd_root

    rel, _ = SHIPPED_URDFS["ur10"]
    return str(erd_root() / rel)


def _excite(tmp_path, capsys, model, *args, end_link="tool0"):
    out = tmp_path / "cmd.csv"
    argv = ["excite", "--model", model, *(["--end-link", end_link] if end_link else []),
            *args, "--out", str(out)]
    code = main(argv)
    cap = capsys.readouterr()
    assert "Traceback" not in cap.err
    return code, cap, out


def test_q0_far_outside_the_limits_is_named_and_nothing_written(ur10, tmp_path, capsys):
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", "100", "0", "0", "0", "0", "0",
                             *FAST)
    assert code == 2 and not out.exists()
    assert "--q0: joint 1 (shoulder_pan_joint) is 100 rad, outside its limits " \
           "[-6.28319, 6.28319] rad" in cap.err
    assert "did you type degrees? use --deg, or give radians" in cap.err


def test_q0_typed_in_degrees_is_caught_and_deg_reads_it(ur10, tmp_path, capsys):
    q0 = ["0", "-70", "70", "-85", "-85", "0"]
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", *q0, *FAST)
    assert code == 2 and "joint 2 (shoulder_lift_joint) is -70 rad" in cap.err
    assert "did you type degrees? use --deg" in cap.err and not out.exists()
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", *q0, "--deg", "--amplitude",
                             "20", *FAST)
    assert code == 0, cap.err
    n_comments = sum(ln.startswith("#") for ln in out.read_text().splitlines())
    data = np.loadtxt(out, delimiter=",", skiprows=n_comments + 1)
    np.testing.assert_allclose(data[0, 1:], np.radians([float(v) for v in q0]), atol=1e-12)
    assert np.abs(data[:, 1:] - np.radians([float(v) for v in q0])).max() <= np.radians(20)


def test_huge_period_times_rate_is_refused_before_allocating(ur10, tmp_path, capsys):
    start = time.perf_counter()
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", "0", "-1.2", "1.2", "-1.5",
                             "-1.5", "0", "--period", "3600", "--rate", "100000")
    assert code == 2 and not out.exists()
    assert "--rate: a period of 3600 s at 100000 Hz is 360,000,000 samples; at most " \
           "200,000" in cap.err
    assert time.perf_counter() - start < 20.0  # the arm loads; no 13 GiB asked


@pytest.mark.parametrize(("args", "message"), [
    (["--max-velocity", "3"], "--max-velocity: joint 1 (shoulder_pan_joint) 3 rad/s is above "
                              "the model's own limit 2.16 rad/s"),
    (["--max-torque", "400"], "--max-torque: joint 1 (shoulder_pan_joint) 400 N m is above "
                              "the model's own limit 330 N m"),
    (["--amplitude", "2"], "--amplitude: joint 3 (elbow_joint) would move over"),
    (["--rate", "1", "--harmonics", "5"], "--rate: 1 Hz is below 20 samples a cycle"),
])
def test_limits_beyond_the_arm_are_named(ur10, tmp_path, capsys, args, message):
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", "0", "-1.2", "1.2", "-1.5",
                             "-1.5", "0", "--candidates", "1", "--iterations", "0", *args)
    assert code == 2 and message in cap.err and not out.exists()


@pytest.mark.parametrize(("args", "message"), [
    (["--harmonics", "1000"], "--harmonics: expected a whole number from 2 to 50"),
    (["--amplitude", "0"], "--amplitude: "),
    (["--candidates", "1000000"], "--candidates: expected a whole number from 1 to 1000"),
])
def test_bounds_stated_at_parsing(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(["excite", "--model", "puma", "--q0", "0", "0", "0", "0", "0", "0", *args,
              "--out", str(tmp_path / "c.csv")])
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_the_command_file_records_its_conditions(ur10, tmp_path, capsys):
    code, cap, out = _excite(tmp_path, capsys, ur10, "--q0", "0", "-1.2", "1.2", "-1.5",
                             "-1.5", "0", "--max-velocity", "0.8", *FAST)
    assert code == 0, cap.err
    lines = out.read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    header = lines[len(comments)].split(",")
    assert header == ["t [s]"] + [f"qc{k} [rad]" for k in range(1, 7)]
    text = "\n".join(comments)
    for key in ("# zrp: ", "# model: ur10_robot.urdf (sha256 ", "# q0 [rad]: 0 -1.2 1.2",
                "# period [s]: 10", "# rate [Hz]: 100", "# velocity limits [rad/s]: 0.8",
                "# torque limits [N m]: 330 330 150 54 54 54 (model",
                "# position limits [rad]: lower -6.28319", "# units: "):
        assert key in text, key
    assert "every one within the position, velocity, acceleration and torque" in cap.out


def test_out_equal_to_model_is_refused_even_with_force(ur10, tmp_path, capsys):
    model = tmp_path / "ur10.urdf"
    model.write_bytes(open(ur10, "rb").read())
    before = model.read_bytes()
    code = main(["excite", "--model", str(model), "--end-link", "tool0", "--q0", "0", "-1.2",
                 "1.2", "-1.5", "-1.5", "0", *FAST, "--out", str(model), "--force"])
    err = capsys.readouterr().err
    assert code == 2 and "is the model file" in err
    assert model.read_bytes() == before
