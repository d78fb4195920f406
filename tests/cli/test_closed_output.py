"""A command whose output is closed early (``zrp fk --json | head -c 10``) ends without a
traceback and with status 141 (128 + SIGPIPE), in every command, and one whose output is on a
full device (``> /dev/full``) says so in one line: ``zrp.cli.app.main`` handles both once
(``zrp.cli.streams``). Each command runs in a fresh interpreter whose stdout
is a pipe whose reader has already gone: the same as ``| head`` having exited, without a race."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from zrp.cli.streams import CLOSED_EXIT

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX pipes")

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


def _closed_pipe_run(args: list[str], cwd: Path, stderr_too: bool = False,
                     ) -> subprocess.CompletedProcess[str]:
    r, w = os.pipe()
    os.close(r)  # the reader is gone before the command writes a byte
    try:
        return subprocess.run(args, stdout=w, stderr=w if stderr_too else subprocess.PIPE,
                              text=True, cwd=cwd, env=ENV, timeout=300)
    finally:
        os.close(w)


def _zrp(argv: list[str], cwd: Path, **kw) -> subprocess.CompletedProcess[str]:
    return _closed_pipe_run([sys.executable, "-m", "zrp", *argv], cwd, **kw)


@pytest.mark.parametrize("argv", [
    ["fk", "--deg", "--q", "0", "0", "0", "0", "90", "0", "--json"],
    ["fk", "--deg", "--q", "0", "0", "0", "0", "90", "0"],
    ["models"],
    ["measure", "--model", "puma", "--poses", "20", "--out", "m.csv"],
])
def test_a_closed_stdout_ends_quietly_with_the_sigpipe_status(argv, tmp_path):
    res = _zrp(argv, tmp_path)
    assert "Traceback" not in res.stderr and "Exception ignored" not in res.stderr, res.stderr
    assert res.stderr == ""
    assert res.returncode == CLOSED_EXIT == 141


def test_the_work_is_done_before_the_output_is_lost(tmp_path):
    # measure writes its files, then prints its summary into the closed pipe
    _zrp(["measure", "--model", "puma", "--poses", "20", "--out", "m.csv"], tmp_path)
    assert (tmp_path / "m.csv").stat().st_size > 0 and (tmp_path / "m.truth.json").exists()


def test_help_into_a_closed_pipe_has_no_traceback(tmp_path):
    for argv in (["--help"], ["plan", "--help"], ["--version"]):
        res = _zrp(argv, tmp_path)
        assert res.stderr == "" and res.returncode in (0, CLOSED_EXIT), (argv, res)


def test_an_error_into_a_closed_pipe_2_and_1(tmp_path):
    # `zrp fk --q 0 0 2>&1 | head -0`: the one-line error itself meets the closed pipe; with no
    # handler Python would end with status 1 (traceback) or 120 (failed final flush)
    res = _zrp(["fk", "--q", "0", "0"], tmp_path, stderr_too=True)
    assert res.returncode == CLOSED_EXIT


def test_a_command_started_with_stdout_closed(tmp_path):
    # `zrp fk >&-`: Python sets sys.stdout to None and print writes nothing; not an error
    res = subprocess.run(["sh", "-c", f"exec {sys.executable} -m zrp fk --q 0 0 0 0 0 0 >&-"],
                         stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=ENV, timeout=300)
    assert res.returncode == 0 and res.stderr == "", res.stderr


def test_a_broken_pipe_elsewhere_is_not_hidden(tmp_path):
    # stdout open and read: a BrokenPipeError from inside the command (a subprocess, a
    # connection) is not the reader going away and still shows as the failure it is
    res = _fk_raising("BrokenPipeError(32, 'Broken pipe')", tmp_path)
    assert res.returncode == 1 and "BrokenPipeError" in res.stderr


def _fk_raising(exc: str, tmp_path):
    """`zrp fk` in a subprocess whose command raises ``exc`` (Python source)."""
    code = ("import sys\nfrom zrp.cli.commands import kin\n"
            f"def boom(args):\n    raise {exc}\n"
            "kin._fk = boom\nfrom zrp.cli.app import main\n"
            "sys.exit(main(['fk', '--q', '0', '0', '0', '0', '0', '0']))")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=tmp_path, env=ENV, timeout=300)


def test_the_closed_stream_is_pointed_at_devnull(tmp_path):
    # the recipe: after the handler, fd 1 is os.devnull, so the final flush cannot fail
    code = ("import os, sys\nfrom zrp.cli.streams import closed_output\n"
            "ok = closed_output()\nnull = os.stat(os.devnull)\nst = os.fstat(1)\n"
            "sys.exit(0 if ok and (st.st_rdev, st.st_ino) == (null.st_rdev, null.st_ino) "
            "else 3)")
    res = _closed_pipe_run([sys.executable, "-c", code], tmp_path)
    assert res.returncode == 0, res.stderr
    with open(tmp_path / "out.txt", "w") as fh:  # an open file: nothing was closed
        res = subprocess.run([sys.executable, "-c", "from zrp.cli.streams import closed_output\n"
                              "import sys\nsys.exit(5 if closed_output() else 0)"],
                             stdout=fh, stderr=subprocess.PIPE, text=True, env=ENV, timeout=300)
    assert res.returncode == 0, res.stderr


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="Linux's /dev/full")
@pytest.mark.parametrize("argv", [["fk", "--q", "0", "0", "0", "0", "0", "0", "--json"],
                                  ["models"]])
def test_output_on_a_full_device_is_one_line(argv, tmp_path):
    with open("/dev/full", "w") as full:
        res = subprocess.run([sys.executable, "-m", "zrp", *argv], stdout=full,
                             stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=ENV,
                             timeout=300)
    assert res.returncode == 2
    assert res.stderr == (f"zrp {argv[0]}: error: cannot write the output (No space left on "
                          "device)\n")


def test_another_os_error_is_not_hidden(tmp_path):
    # only a device's errors (no space, quota, I/O) are the environment's; any other OSError
    # escaping a command is unexpected and keeps its traceback
    res = _fk_raising("PermissionError(13, 'Permission denied')", tmp_path)
    assert res.returncode == 1 and "PermissionError" in res.stderr
