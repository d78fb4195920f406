"""Another distribution's ``sim`` or ``mjcf`` (or a folder of that name in the current
directory) must give one clear message naming both places, not an obscure ImportError."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import mjcf
import sim
from zrp.packages import DISTRIBUTION, PackageShadowedError, check_own_packages


def _fake_package(root: Path, name: str) -> Path:
    """A package ``name`` under ``root`` that fails obscurely when imported."""
    pkg = root / name
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("raise ImportError('some other project')\n")
    return pkg


def test_our_packages_say_which_distribution_they_belong_to():
    assert sim.__distribution__ == mjcf.__distribution__ == DISTRIBUTION == "zrp-accuracy"
    check_own_packages()  # nothing shadows them here


def test_a_shadowing_package_on_sys_path_is_named(tmp_path, monkeypatch):
    fake = _fake_package(tmp_path, "sim")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "sim")  # the check looks before the first import
    with pytest.raises(PackageShadowedError, match="shadows it") as info:
        check_own_packages()
    assert str(fake) in str(info.value) and "'sim'" in str(info.value)
    assert isinstance(info.value, ImportError)


@pytest.mark.parametrize("name", ["sim", "mjcf"])
def test_the_command_line_names_a_shadowing_folder_in_the_current_directory(tmp_path, name):
    fake = _fake_package(tmp_path, name)
    run = subprocess.run([sys.executable, "-m", "zrp", "ik"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr and "some other project" not in run.stderr
    assert f"own {name!r} package" in run.stderr and str(fake) in run.stderr


def test_sim_names_a_shadowing_mjcf_before_importing_it(tmp_path):
    _fake_package(tmp_path, "mjcf")
    run = subprocess.run([sys.executable, "-c", "import sim"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 1
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("zrp.packages.PackageShadowedError") and "'mjcf'" in last
    assert "some other project" not in run.stderr
