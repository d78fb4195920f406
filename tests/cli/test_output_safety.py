"""The output policy's boundary (zrp.output): only regular files are replaced (symbolic links,
devices, FIFOs and symlinked output folders are refused by name, even with --force); names too
long for the file system are named errors; a held lock is waited for at most a bounded time and
then named with its holder's pid; a rerun removes the files of an earlier run it does not make.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest

from zrp.cli import main
from zrp.errors import InputError, OutputBusyError, OutputKindError
from zrp.output import LOCK_NAME, OutputDir, check_writable, write_text


def _special(tmp: Path) -> dict[str, Path]:
    """A symbolic link to the standard output, a dangling link, a FIFO and (as root) a
    character device like /dev/null, all inside ``tmp``."""
    nodes = {"link_to_stdout": tmp / "stdout_link", "dangling_link": tmp / "dangling",
             "fifo": tmp / "fifo"}
    os.symlink("/proc/self/fd/1", nodes["link_to_stdout"])
    os.symlink(tmp / "nowhere", nodes["dangling_link"])
    os.mkfifo(nodes["fifo"])
    if os.geteuid() == 0:
        nodes["char_device"] = tmp / "null"
        os.mknod(nodes["char_device"], stat.S_IFCHR | 0o600, os.makedev(1, 3))
    return nodes


@pytest.mark.parametrize("kind", ["link_to_stdout", "dangling_link", "fifo", "char_device"])
def test_force_replaces_only_regular_files(tmp_path, kind):
    nodes = _special(tmp_path)
    if kind not in nodes:
        pytest.skip("a device node needs root")
    node = nodes[kind]
    before = os.lstat(node)
    with pytest.raises(OutputKindError, match=r"symbolic link|FIFO|character device"):
        write_text(node, "replaced", overwrite=True)
    after = os.lstat(node)
    assert stat.S_IFMT(after.st_mode) == stat.S_IFMT(before.st_mode)  # the node is kept
    assert after.st_ino == before.st_ino


def test_the_systems_dev_null_is_refused_before_writing():
    # checked only (never written): as root, `--out /dev/null --force` used to replace it
    with pytest.raises(OutputKindError, match="character device"):
        check_writable(["/dev/null"], overwrite=True)


@pytest.mark.parametrize("kind", ["link_to_stdout", "fifo", "char_device"])
def test_export_force_onto_a_special_file_is_a_named_error(tmp_path, kind, capsys):
    nodes = _special(tmp_path)
    if kind not in nodes:
        pytest.skip("a device node needs root")
    node = nodes[kind]
    mode = os.lstat(node).st_mode
    assert main(["export", "--to", "urdf", "--out", str(node), "--force"]) == 2
    err = capsys.readouterr().err
    assert str(node) in err and "regular file" in err, err
    assert os.lstat(node).st_mode == mode


def test_a_symlinked_output_folder_is_refused_not_written_through(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real)
    with pytest.raises(OutputKindError, match=r"symbolic link .*refused, not resolved"), \
            OutputDir(tmp_path / "link", overwrite=True) as out:
        out.write_text("a.txt", "x")
    assert list(real.iterdir()) == []
    sub = tmp_path / "o"
    sub.mkdir()
    (sub / "plots").symlink_to(real)
    with pytest.raises(OutputKindError, match="inside the output folder"), \
            OutputDir(sub, overwrite=True) as out:
        out.write_text("plots/a.txt", "x")
    assert list(real.iterdir()) == []


def test_fleet_resume_does_not_write_through_a_symlinked_robot_folder(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    robots = tmp_path / "fleet" / "robots"
    robots.mkdir(parents=True)
    (robots / "r1").symlink_to(elsewhere)
    with pytest.raises(OutputKindError), OutputDir(robots / "r1", overwrite=True) as out:
        out.write_text("diagnosis.json", "{}")
    assert list(elsewhere.iterdir()) == []


def test_a_name_too_long_is_a_named_error(tmp_path, capsys):
    long = tmp_path / ("x" * 300)
    with pytest.raises(InputError, match="name too long"):
        write_text(long / "a.txt", "x")
    with pytest.raises(InputError, match="name too long"), OutputDir(long):
        pass
    assert main(["export", "--to", "urdf", "--out", str(tmp_path / ("y" * 300 + ".urdf"))]) == 2
    assert "name too long" in capsys.readouterr().err
    # the longest name the file system allows is written (its temporary name is short)
    ok = tmp_path / ("z" * 250 + ".txt")
    write_text(ok, "fits")
    assert ok.read_text() == "fits"


def test_a_lock_held_by_a_live_process_is_waited_for_then_named(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK_NAME).write_text(f"{holder.pid} {socket.gethostname()}\n")
        t0 = time.monotonic()
        with pytest.raises(OutputBusyError) as info, OutputDir(tmp_path, lock_wait_s=0.5):
            pass
        waited = time.monotonic() - t0
    finally:
        holder.kill()
        holder.wait()
    msg = str(info.value)
    assert str(tmp_path / LOCK_NAME) in msg and f"process {holder.pid}" in msg, msg
    assert 0.4 < waited < 30  # bounded: the wait, not forever
    with OutputDir(tmp_path, lock_wait_s=0.5) as out:  # the holder ended: taken over
        out.write_text("x.txt", "ok")


def test_a_lock_that_is_a_fifo_does_not_hang(tmp_path):
    os.mkfifo(tmp_path / LOCK_NAME)
    with pytest.raises(OutputKindError, match="lock"), OutputDir(tmp_path, lock_wait_s=0.5):
        pass


def test_a_rerun_removes_the_outputs_it_no_longer_makes(tmp_path):
    names = ("report.md", "plot.png")
    with OutputDir(tmp_path, names=names, prune=True) as out:
        out.write_text("report.md", "with plot")
        out.write_bytes("plot.png", b"png")
    (tmp_path / "mine.txt").write_text("the user's")
    with OutputDir(tmp_path, overwrite=True, names=names, prune=True) as out:
        out.write_text("report.md", "no plot")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt", "report.md"]
    assert [p.name for p in out.removed] == ["plot.png"]
    # a failed run removes nothing
    with pytest.raises(RuntimeError), \
            OutputDir(tmp_path, overwrite=True, names=("report.md",), prune=True):
        raise RuntimeError("failed")
    assert (tmp_path / "report.md").read_text() == "no plot"


def test_diagnose_force_no_plots_leaves_no_stale_plot(tmp_path, measured_csv):
    out = tmp_path / "diag"
    argv = ["diagnose", "--model", "puma", "--data", str(measured_csv), "--max-steps", "1",
            "--out", str(out)]
    assert main(argv) == 0
    assert (out / "shrink.png").is_file()
    assert "shrink.png" in (out / "report.md").read_text()
    assert main([*argv, "--force", "--no-plots"]) == 0
    assert not list(out.glob("*.png"))
    assert ".png" not in (out / "report.md").read_text()


@pytest.mark.parametrize("make", [
    lambda tmp: tmp / ("8" * 400),                       # over the file system's name limit
    lambda tmp: tmp / "a-file" / "out",                  # a file where a folder must be
])
def test_an_output_folder_the_file_system_refuses_is_one_named_line(tmp_path, capsys, make):
    """OSError of a file name the user gave (ENAMETOOLONG, ENOTDIR, ...): exit 2 and one line
    naming the file, never a traceback (found by the hostile-input pass, issue 35)."""
    (tmp_path / "a-file").write_text("x")
    out = make(tmp_path)
    data = tmp_path / "d.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["measure", "--out", str(data), "--poses", "30", "--seed", "1"]) == 0
        capsys.readouterr()
        rc = main(["diagnose", "--model", "puma", "--data", str(data), "--out", str(out),
                   "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert err.startswith("zrp diagnose: error: ") and len(err.strip().splitlines()) == 1
    assert str(out)[:40] in err
