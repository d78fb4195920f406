"""The command line: subcommands, JSON output, clear errors."""

import json
import subprocess
import sys

import numpy as np

from zrp.cli.app import main


def test_help_lists_subcommands(capsys):
    try:
        main(["--help"])
    except SystemExit:
        pass
    out = capsys.readouterr().out
    for cmd in ("fk", "ik", "models"):
        assert cmd in out


def test_fk_json(capsys):
    assert main(["fk", "--q", "0", "0", "0", "0", "0", "0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(data["position"], [431.8, 254.0, -558.8])
    assert data["euler_rodrigues"] == [1.0, 0.0, 0.0, 0.0]


def test_ik_json_writes_csv(tmp_path, capsys):
    out = tmp_path / "joints.csv"
    assert main(["ik", "--steps", "200", "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["max_position_error"] < 1e-9
    assert out.exists()
    # refuses to overwrite without --force
    assert main(["ik", "--steps", "200", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["ik", "--steps", "200", "--out", str(out), "--force"]) == 0


def test_errors_are_one_line_not_tracebacks(capsys):
    assert main(["fk", "--q", "0", "0"]) == 2
    err = capsys.readouterr().err
    assert "expected 6 values" in err and "Traceback" not in err
    assert main(["fk", "--model", "nope.toml", "--q", "0"]) == 2
    assert "built-in models are" in capsys.readouterr().err


def test_console_entry_point_runs():
    res = subprocess.run([sys.executable, "-m", "zrp", "models", "--json"], capture_output=True,
                         text=True, check=True)
    assert "puma" in json.loads(res.stdout)
