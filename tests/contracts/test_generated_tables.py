"""Standing result tables in the READMEs are generated, never typed: each block between
``<!-- generated: NAME ... -->`` markers carries the digest of its text (an edit by hand
breaks it), and when the benchmark's report is present the block is exactly the one its JSON
gives (tests/benchmarks/_readme_block.py)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "tests" / "benchmarks"
BLOCKS = (("bench_arms", ROOT / "sim" / "README.md"),
          ("bench_dynamics", ROOT / "zrp" / "gap" / "dynamics" / "README.md"),
          ("bench_dynamics_reallogs", ROOT / "sim" / "README.md"),
          ("bench_figaroh", ROOT / "zrp" / "gap" / "README.md"))
#: The benchmarks whose --quick runs leave the README as it is (the others write it, saying
#: the size they ran at in the block's heading).
QUICK_SKIPS_README = {"bench_arms", "bench_dynamics_reallogs", "bench_figaroh"}


def _block_module():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("_readme_block", BENCH / "_readme_block.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    finally:
        sys.path.remove(str(BENCH))


@pytest.mark.parametrize(("name", "readme"), BLOCKS, ids=[b[0] for b in BLOCKS])
def test_the_block_is_there_once_and_untouched(name, readme):
    mod = _block_module()
    found = mod.read_block(readme, name)
    assert found is not None, f"{readme.name}: no (or more than one) generated block {name}"
    recorded, body = found
    assert recorded == mod.digest(body), (
        f"{readme.name}: the generated {name} table was edited by hand; run "
        f"tests/benchmarks/{name}.py again")


@pytest.mark.parametrize(("name", "readme"), BLOCKS, ids=[b[0] for b in BLOCKS])
def test_the_block_is_the_reports_table(name, readme):
    report = ROOT / "renders" / "benchmarks" / f"{name}.json"
    if not report.is_file():
        pytest.skip(f"renders/benchmarks/{name}.json not generated in this checkout")
    data = json.loads(report.read_text(encoding="utf-8"))
    quick = "--quick" in data["command"] and name in QUICK_SKIPS_README
    if quick or "--out" in data["command"] or "--no-readme" in data["command"]:
        pytest.skip(f"the last {name} run did not write the README (quick or elsewhere)")
    mod = _block_module()
    sec = data["sections"][0]
    expected = mod.block_text(sec["heading"], sec["columns"], sec["rows"], data,
                              mod.readme_sections(data))
    assert mod.read_block(readme, name)[1] == expected


def test_an_edit_by_hand_is_caught(tmp_path):
    mod = _block_module()
    readme = tmp_path / "README.md"
    readme.write_text("# x\n\n<!-- generated: t by tests/benchmarks/t.py; do not edit (run it "
                      "again); sha256=0 -->\nold\n<!-- end generated: t -->\n", encoding="utf-8")
    meta = {"date": "d", "command": "c", "versions": {"zrp": "v"}}
    mod.replace_block(readme, "t", "h", ["a", "b"], [["1", "2"]], meta)
    recorded, body = mod.read_block(readme, "t")
    assert recorded == mod.digest(body) and "| 1 | 2 |" in body
    readme.write_text(readme.read_text(encoding="utf-8").replace("| 1 |", "| 9 |"),
                      encoding="utf-8")
    recorded, body = mod.read_block(readme, "t")
    assert recorded != mod.digest(body)
