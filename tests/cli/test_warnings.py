"""Warnings print the same way in every command: one line ``zrp CMD: warning: message``, each
distinct message once, never Python's file:line with the source line. Run as a user runs them
(a fresh process: pytest records warnings itself, and the commands leave a caller's record
alone)."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from zrp.cli.app import one_line_warnings

ROOT = Path(__file__).resolve().parents[2]


def _run(argv: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True, cwd=ROOT,
                          timeout=600)


def _check(err: str, command: str) -> list[str]:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    warned = [ln for ln in lines if "warning" in ln.lower()]
    assert all(ln.startswith(f"zrp {command}: warning: ") for ln in warned), err
    assert "warnings.warn(" not in err and ".py:" not in err, err
    assert len(warned) == len(set(warned)), err
    return warned


@pytest.mark.parametrize("command", ["calibrate", "diagnose"])
def test_calibrate_and_diagnose_print_warnings_as_one_line(command, tmp_path, measured_csv):
    argv = ["-m", "zrp", command, "--model", "puma", "--data", str(measured_csv),
            "--max-steps", "1", "--out", str(tmp_path / "o")]
    if command == "diagnose":
        argv.append("--no-plots")
    run = _run(argv)
    assert run.returncode == 0, run.stderr
    assert _check(run.stderr, command), "the 40-pose file gives at least one data warning"


def test_one_line_warnings_collapses_lines_and_repeats():
    code = ("import warnings\nfrom zrp.cli.app import one_line_warnings\n"
            "with one_line_warnings('zrp x'):\n"
            "    for _ in range(3):\n"
            "        warnings.warn('two\\nlines', UserWarning, stacklevel=1)\n")
    run = _run(["-c", code])
    assert run.stderr == "zrp x: warning: two lines\n", run.stderr


def test_a_callers_record_still_gets_the_warnings():
    with pytest.warns(UserWarning, match="kept"), one_line_warnings("zrp x"):
        warnings.warn("kept for the caller", UserWarning, stacklevel=1)
