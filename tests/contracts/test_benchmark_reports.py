"""Measured results are generated, not typed: every benchmark script writes its tables through
tests/benchmarks/_report.py into renders/benchmarks/<name>.md (+ .json), stating the date,
machine, versions and command, and `zrp index` links them."""

from __future__ import annotations

import argparse
import ast
import importlib.util
import json
from pathlib import Path

import pytest

from zrp.paper.index import index_entries, index_html

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "tests" / "benchmarks"
SCRIPTS = sorted(BENCH.glob("bench_*.py"))


def _report_module():
    spec = importlib.util.spec_from_file_location("_bench_report", BENCH / "_report.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _args(rep, name: str, argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser()
    rep.add_output_arguments(ap, name)
    return ap.parse_args(argv)


def _calls(tree: ast.AST) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            names.add(f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", ""))
    return names


def test_there_are_benchmark_scripts():
    assert len(SCRIPTS) >= 9, [s.name for s in SCRIPTS]


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_each_script_writes_its_tables_through_the_report(script):
    tree = ast.parse(script.read_text(encoding="utf-8"))
    calls = _calls(tree)
    missing = {"add_output_arguments", "output_path", "Report", "write"} - calls
    assert not missing, f"{script.name} does not call {sorted(missing)}"
    names = [a.args[1].value for a in ast.walk(tree) if isinstance(a, ast.Call)
             and getattr(a.func, "id", "") == "add_output_arguments"
             and len(a.args) == 2 and isinstance(a.args[1], ast.Constant)]
    assert names == [script.stem], f"{script.name}: report name {names}, expected the stem"
    assert "--quick" in script.read_text(encoding="utf-8"), f"{script.name} has no --quick"


def test_report_states_date_machine_versions_and_command(tmp_path):
    rep = _report_module()
    out = tmp_path / "sub" / "bench_x.md"
    args = _args(rep, "bench_x", ["--out", str(out)])
    assert rep.output_path(args) == out
    r = rep.Report("bench_x", "a test table")
    r.table("Speed", ["figure", "value"], [("a|b", "1.0"), ("c", 2)], note="a note")
    r.write(out, args, argv=[str(BENCH / "bench_x.py"), "--quick"])
    text = out.read_text(encoding="utf-8")
    for needle in ("# bench_x: a test table", "| date | ", " cores, ", "| versions | python ",
                   "numpy ", "zrp ", "`python3 tests/benchmarks/bench_x.py --quick`",
                   "## Speed", "| figure | value |", "| a\\|b | 1.0 |", "| c | 2 |", "a note"):
        assert needle in text, needle
    data = json.loads(out.with_suffix(".json").read_text(encoding="utf-8"))
    assert data["command"] == "python3 tests/benchmarks/bench_x.py --quick"
    assert data["machine"]["cores"] >= 1 and data["versions"]["numpy"]
    assert data["sections"][0]["rows"] == [["a|b", "1.0"], ["c", "2"]]


def test_an_explicit_out_is_not_replaced_without_force(tmp_path, capsys):
    rep = _report_module()
    out = tmp_path / "bench_x.md"
    out.write_text("mine\n", encoding="utf-8")
    with pytest.raises(SystemExit) as exc:
        rep.output_path(_args(rep, "bench_x", ["--out", str(out)]))
    assert exc.value.code == 2
    assert "--force" in capsys.readouterr().err
    assert out.read_text(encoding="utf-8") == "mine\n"
    args = _args(rep, "bench_x", ["--out", str(out), "--force"])
    rep.output_path(args)
    rep.Report("bench_x", "t").write(out, args, argv=["bench_x.py"])
    assert out.read_text(encoding="utf-8").startswith("# bench_x: t")


def test_out_must_be_markdown(tmp_path):
    rep = _report_module()
    with pytest.raises(SystemExit):
        rep.output_path(_args(rep, "bench_x", ["--out", str(tmp_path / "x.txt")]))


def test_default_is_renders_benchmarks():
    rep = _report_module()
    assert rep.default_path("bench_x") == ROOT / "renders" / "benchmarks" / "bench_x.md"


def test_index_links_the_benchmark_results(tmp_path):
    bench = tmp_path / "benchmarks"
    (bench / "bench_gap_benchmark").mkdir(parents=True)
    for name in ("bench_x.md", "bench_x.json", "bench_gap_benchmark/summary.md"):
        (bench / name).write_text("x\n", encoding="utf-8")
    sentences = dict(index_entries(tmp_path))
    assert sentences["benchmarks/bench_x.md"].startswith("Measured results of a benchmark")
    assert sentences["benchmarks/bench_x.json"].startswith("The same measured results")
    assert "detailed tables" in sentences["benchmarks/bench_gap_benchmark/summary.md"]
    assert 'href="benchmarks/bench_x.md"' in index_html(tmp_path)
