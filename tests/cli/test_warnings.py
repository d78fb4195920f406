"""Warnings print the same way in every command: one line ``zrp CMD: warning: message``, each
distinct message once, never Python's file:line with the source line."""

from __future__ import annotations

import warnings

import pytest

from zrp.cli import main
from zrp.cli.app import one_line_warnings


def _check(err: str, command: str) -> list[str]:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    warned = [ln for ln in lines if "warning" in ln.lower()]
    assert all(ln.startswith(f"zrp {command}: warning: ") for ln in warned), err
    assert "warnings.warn(" not in err and ".py:" not in err, err
    assert len(warned) == len(set(warned)), err
    return warned


@pytest.mark.parametrize("command", ["calibrate", "diagnose"])
def test_calibrate_and_diagnose_print_warnings_as_one_line(command, tmp_path, measured_csv,
                                                           capsys):
    argv = [command, "--model", "puma", "--data", str(measured_csv), "--max-steps", "1",
            "--out", str(tmp_path / "o")]
    if command == "diagnose":
        argv.append("--no-plots")
    assert main(argv) == 0
    warned = _check(capsys.readouterr().err, command)
    assert warned, "the 40-pose file gives at least one data warning"


def test_one_line_warnings_collapses_lines_and_repeats(capsys):
    with one_line_warnings("zrp x"):
        for _ in range(3):
            warnings.warn("two\nlines", UserWarning, stacklevel=1)
    assert capsys.readouterr().err == "zrp x: warning: two lines\n"
