"""Every command that writes has --force, never replaces a file the user has without it (and
says so before doing the work), and refuses an output folder another run is writing into."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest

from zrp.cli import build_parser, main
from zrp.output import LOCK_NAME

OUTPUT_OPTIONS = {"--out", "--hist", "--truth", "--workdir"}


def subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def test_every_command_that_writes_has_force():
    writers = {}
    for name, p in subcommands().items():
        opts = {o for a in p._actions for o in a.option_strings}
        if opts & OUTPUT_OPTIONS:
            writers[name] = "--force" in opts
    assert len(writers) >= 9, writers
    assert all(writers.values()), {k: v for k, v in writers.items() if not v}


def cases(tmp: Path, data: Path) -> dict[str, tuple[list[str], Path]]:
    """argv and the output (file or folder) of a quick run of each writing command."""
    return {
        "ik": (["ik", "--steps", "40", "--out", str(tmp / "j.csv")], tmp / "j.csv"),
        "mjcf": (["mjcf", "--out", str(tmp / "m.xml")], tmp / "m.xml"),
        "study": (["study", "--steps", "40", "--params", "LE2", "--xi", "0.1",
                   "--out", str(tmp / "study")], tmp / "study"),
        "tolerance": (["tolerance", "--robots", "100", "--steps", "40", "--no-progress",
                       "--hist", str(tmp / "h.png")], tmp / "h.png"),
        "paper": (["paper", "--steps", "40", "--no-video", "--no-plots",
                   "--out", str(tmp / "paper")], tmp / "paper"),
        "diagnose": (["diagnose", "--model", "puma", "--data", str(data), "--max-steps", "1",
                      "--no-plots", "--out", str(tmp / "diag")], tmp / "diag"),
        "measure": (["measure", "--poses", "8", "--out", str(tmp / "meas.csv")],
                    tmp / "meas.csv"),
    }


def snapshot(target: Path) -> dict[str, bytes]:
    files = [target] if target.is_file() else sorted(p for p in target.rglob("*") if p.is_file())
    return {str(p): p.read_bytes() for p in files}


QUICK = ("ik", "mjcf", "study", "tolerance", "paper", "diagnose", "measure")


@pytest.mark.parametrize("command", QUICK)
def test_existing_output_is_refused_without_force(command, tmp_path, measured_csv, capsys):
    argv, target = cases(tmp_path, measured_csv)[command]
    assert main(argv) == 0, capsys.readouterr().err
    before = snapshot(target)
    assert before
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--force" in err and "overwrite=True" not in err, err
    assert err.count("\n") == 1, err  # one clear line, no traceback
    assert snapshot(target) == before  # nothing replaced
    assert main([*argv, "--force"]) == 0


FOLDER_COMMANDS = ("study", "paper", "diagnose")


@pytest.mark.parametrize("command", FOLDER_COMMANDS)
def test_a_folder_another_run_writes_into_is_refused(command, tmp_path, measured_csv, capsys):
    argv, target = cases(tmp_path, measured_csv)[command]
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        import socket

        target.mkdir(parents=True)
        (target / LOCK_NAME).write_text(f"{holder.pid} {socket.gethostname()}\n")
        assert main([*argv, "--force"]) == 2
        err = capsys.readouterr().err
        assert f"process {holder.pid}" in err and "is writing into this folder" in err, err
        assert sorted(p.name for p in target.iterdir()) == [LOCK_NAME]  # nothing written
    finally:
        holder.kill()
        holder.wait()
    assert main([*argv, "--force"]) == 0  # the holder ended: its lock is stale, taken over
    assert not (target / LOCK_NAME).exists()


def test_two_concurrent_cli_runs_into_one_folder_never_mix(tmp_path, measured_csv):
    """Two real `zrp diagnose` processes started together into one folder: one writes, the
    other is refused (or waits its turn and is refused for existing files); the folder holds
    the whole output of exactly one run."""
    out = tmp_path / "diag"
    argv = [sys.executable, "-m", "zrp", "diagnose", "--model", "puma", "--data",
            str(measured_csv), "--max-steps", "1", "--no-plots", "--out", str(out)]
    fractions = ("0.2", "0.3")
    procs = [subprocess.Popen([*argv, "--withheld", f], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for f in fractions]
    results = [(p.wait(300), p.stderr.read()) for p in procs]
    codes = sorted(rc for rc, _ in results)
    assert codes == [0, 2], results
    refused = next(err for rc, err in results if rc == 2)
    assert "is writing into this folder" in refused or "--force" in refused, refused
    winner = fractions[[rc for rc, _ in results].index(0)]
    doc = json.loads((out / "diagnosis.json").read_text())
    assert doc["split"]["withheld_fraction"] == float(winner)
    rows = (out / "residuals.csv").read_text().splitlines()
    n_withheld = len({r.split(",")[1] for r in rows[1:]})
    assert n_withheld == len(doc["split"]["withheld"])  # the CSV is the same run's
    assert not (out / LOCK_NAME).exists()
