"""The dynamic gap's blind benchmark: the truth never reaches the diagnosis, and a seeded
reduced run names the hidden effects with the withheld torque error near the noise."""

from __future__ import annotations

import builtins
import io
import json
from pathlib import Path

import pytest

from sim.studies.dynamics import benchmark as bm
from sim.studies.dynamics.scenarios import Scenario


@pytest.mark.slow
def test_truth_never_reaches_the_diagnosis(tmp_path, monkeypatch):
    sc = Scenario("puma", "coulomb", 3, seconds=10.0)
    csv, truth = bm.simulate_scenario(sc, tmp_path / "logs", tmp_path / "truth")
    opened: list[Path] = []
    real_open, real_io_open = builtins.open, io.open

    def spy(file, *a, **kw):
        if isinstance(file, (str, Path)):
            opened.append(Path(file).resolve())
        return real_open(file, *a, **kw)

    monkeypatch.setattr(builtins, "open", spy)
    monkeypatch.setattr(io, "open", spy)
    before = bm.diagnose_blind(csv, "puma")
    monkeypatch.setattr(builtins, "open", real_open)
    monkeypatch.setattr(io, "open", real_io_open)
    assert csv.resolve() in opened
    assert not any(p.name.endswith(".truth.json") or (tmp_path / "truth") in p.parents
                   for p in opened)
    truth.unlink()
    after = bm.diagnose_blind(csv, "puma")
    assert json.dumps(before) == json.dumps(after)


@pytest.mark.slow
def test_seeded_reduced_run(tmp_path):
    rows = [bm.run_scenario(sc, tmp_path) for sc in
            bm.draw_scenarios(["puma"], ("coulomb", "payload", "none"), 1, seed=1,
                              seconds=15.0)]
    by = {r.kind: r for r in rows}
    assert by["coulomb"].visible and by["coulomb"].success
    assert by["payload"].visible and by["payload"].success
    assert by["none"].named == "none" and by["none"].withheld_ratio <= 1.2
    t = bm.tally(rows)
    assert t["right"] == t["visible_singles"] == 2
