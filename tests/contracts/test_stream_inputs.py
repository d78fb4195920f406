"""Every reader of a user's file goes through the bounded reader (zrp.textio, issue 26): a
FIFO (which would hang), /dev/zero (which grew to 6.6 GB) and a CSV with one endless line are
named errors, at the API and on the command line, before anything is read whole."""

from __future__ import annotations

import os

import pytest

import zrp
from zrp.calibration import read_calibration
from zrp.calibration.planfile import read_plan
from zrp.calibration.targets import load_targets
from zrp.cli import main
from zrp.errors import ZRPError
from zrp.gap import load_measurements
from zrp.gap.motion import load_trajectory
from zrp.manufacturing.study import load_joint_csv
from zrp.model.urdf import import_urdf

PUMA = zrp.load_model("puma")

READERS = {
    "model": lambda p: zrp.load_model(p),
    "urdf": lambda p: import_urdf(p),
    "measurements": lambda p: load_measurements(p, PUMA),
    "trajectory": lambda p: load_trajectory(p, PUMA),
    "targets": lambda p: load_targets(p, 6),
    "joints": lambda p: load_joint_csv(p, PUMA),
    "compensation": lambda p: read_calibration(p),
    "plan": lambda p: read_plan(p, PUMA),
}


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "pipe.csv"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_fifo_is_refused(reader, fifo):
    with pytest.raises(ZRPError, match="FIFO"):
        READERS[reader](fifo)


@pytest.mark.parametrize("reader", sorted(READERS))
def test_dev_zero_is_refused(reader):
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    with pytest.raises(ZRPError, match="character device"):
        READERS[reader]("/dev/zero")


@pytest.mark.parametrize("reader", ["measurements", "trajectory", "targets", "joints"])
def test_one_endless_line_is_refused_at_its_limit(reader, tmp_path):
    f = tmp_path / "long.csv"
    with open(f, "w") as fh:
        fh.write("t,q1," + "1" * (2 * 2**20) + "\n")  # refused before the header is parsed
    with pytest.raises(ZRPError, match="line 1: longer than 1,048,576 characters"):
        READERS[reader](f)


@pytest.mark.parametrize("argv", [
    ["import", "{f}", "--out", "{d}/m.toml"],
    ["diagnose", "--model", "puma", "--data", "{f}", "--out", "{d}/o"],
    ["diagnose-motion", "--model", "puma", "--data", "{f}", "--out", "{d}/o"],
    ["study", "--joints", "{f}"],
    ["tolerance", "--joints", "{f}", "-n", "100", "--no-progress"],
])
def test_the_commands_refuse_a_fifo(argv, fifo, tmp_path, capsys):
    args = [a.format(f=fifo, d=tmp_path) for a in argv]
    assert main(args) != 0
    err = capsys.readouterr().err
    assert "not a regular file" in err and "Traceback" not in err
