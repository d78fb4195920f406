"""The package READMEs' ```python examples run as written (each README's blocks in order, in one
namespace, in a scratch folder), so the reference stays true when the code moves. A block that
only illustrates (it needs a file the reader has, such as a robot's MJCF) is fenced ```py and is
not run. The root README's blocks are run by tests/contracts/test_readme.py."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("zrp/model", "zrp/kinematics", "zrp/manufacturing", "zrp/paper", "zrp/calibration",
            "zrp/cli", "mjcf", "zrp/gap/dynamics")


def python_blocks(readme: Path) -> list[str]:
    text = readme.read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```$", text, flags=re.S | re.M)


@pytest.mark.parametrize("package", PACKAGES)
def test_package_readme_examples_run(package, tmp_path, monkeypatch, capsys):
    readme = ROOT / package / "README.md"
    blocks = python_blocks(readme)
    assert blocks, f"{package}/README.md has no ```python example"
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "__readme__"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the examples' data may warn (aliased parameters)
        for i, block in enumerate(blocks, 1):
            try:
                exec(compile(block, f"{package}/README.md python block {i}", "exec"), namespace)
            except Exception as exc:  # pragma: no cover - the message is the point
                pytest.fail(f"{package}/README.md python block {i} failed: "
                            f"{type(exc).__name__}: {exc}\n{block}")
