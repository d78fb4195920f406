"""The command line starts without the heavy modules: building the parser (``zrp --help``,
``zrp <cmd> --help``) and ``import zrp`` import neither NumPy, SciPy, numba, MuJoCo, Matplotlib
nor Dask; each command imports them when it runs. Checked in a fresh interpreter from
``sys.modules`` (deterministic; the time itself is measured in
tests/benchmarks/bench_cli_startup.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numpy", "scipy", "numba", "mujoco", "matplotlib", "dask", "distributed", "sim",
         "mjcf")


def _loaded(code: str) -> list[str]:
    probe = (f"{code}\nimport sys, json\n"
             f"print(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))")
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
                         timeout=120, check=True)
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_building_the_parser_imports_no_heavy_module():
    assert _loaded("from zrp.cli.app import build_parser\nbuild_parser()") == []


def test_import_zrp_imports_no_heavy_module():
    assert _loaded("import zrp") == []


@pytest.mark.parametrize("argv", [["--help"], ["diagnose", "--help"], ["calibrate", "--help"],
                                  ["tolerance", "--help"], ["paper", "--help"]])
def test_help_imports_no_heavy_module(argv):
    code = ("import contextlib, io\nfrom zrp.cli.app import main\n"
            "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
            f"    main({argv!r})")
    assert _loaded(code) == []


def test_the_names_are_still_there_when_used():
    # the lazy package names resolve to the same objects as the defining modules
    code = ("import zrp, zrp.gap\nfrom zrp.gap.pipeline import diagnose\n"
            "assert zrp.diagnose is diagnose and zrp.gap.diagnose is diagnose\n"
            "assert zrp.gap.report.verdict_text is not None\n"
            "assert set(zrp.__all__) <= set(dir(zrp))")
    assert "scipy" in _loaded(code)
