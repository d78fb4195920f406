"""No silent regressions (issue 34): every set of the regression benchmark
(tests/benchmarks/bench_regression.py) ends at most its stated tolerance above the final
withheld RMS recorded in tests/benchmarks/regression_reference.json."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _bench():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("bench_regression",
                                                      BENCH / "bench_regression.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    finally:
        sys.path.remove(str(BENCH))


def _reference() -> dict:
    return json.loads((BENCH / "regression_reference.json").read_text(encoding="utf-8"))


def test_the_reference_covers_every_set_and_states_its_tolerance():
    mod = _bench()
    ref = _reference()
    assert set(ref["sets"]) == set(mod.SETS)
    assert ref["tolerance"] == mod.TOLERANCE
    assert all(v["final_rms"] > 0 for v in ref["sets"].values())


def test_the_check_catches_a_set_that_got_worse():
    mod = _bench()
    ref = {"tolerance": 0.05, "sets": {"a": {"final_rms": 0.1}, "b": {"final_rms": 0.2}}}
    ok = [{"set": "a", "final_rms": 0.104}, {"set": "b", "final_rms": 0.15}]
    assert mod.regressions(ok, ref) == []
    worse = [{"set": "a", "final_rms": 0.106}, {"set": "c", "final_rms": 0.1}]
    found = mod.regressions(worse, ref)
    assert len(found) == 2 and found[0].startswith("a: final withheld RMS 0.106 > reference")
    assert found[1].startswith("c: not in the reference")


@pytest.mark.slow
def test_no_set_got_worse_than_the_reference():
    pytest.importorskip("mujoco")
    mod = _bench()
    results = [mod.run_set(name) for name in mod.SETS]
    assert mod.regressions(results, _reference()) == []
