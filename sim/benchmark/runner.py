"""Blind benchmark, part 5: the run - draw, simulate, diagnose blind, score - in this process
or in a pool of worker processes (``jobs``; results are identical, each scenario has its own
seed).
"""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from tqdm.auto import tqdm

from mjcf import MJCFOptions, build, save_mjcf
from sim.benchmark.blind import diagnose_blind, simulate_scenario
from sim.benchmark.results import BenchmarkResult
from sim.benchmark.scenarios import BenchmarkConfig, Scenario, draw_scenarios
from sim.benchmark.scoring import ScenarioScore, score
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.output import OutputDir, write_json

__all__ = ["WORK_FOLDERS", "run_benchmark"]

#: Sub-folders of the work folder: what the diagnosis sees, what only the scorer reads, and
#: the diagnoses.
WORK_FOLDERS = ("measurements", "truth", "diagnoses")


def _scenario(model: Manipulator, scn: Scenario, config: BenchmarkConfig, work: Path,
              mjcf_path: Path | None) -> ScenarioScore:
    """Simulate, diagnose blind, then score one scenario (in this process or a worker)."""
    csv_path, truth_path, sim_s = simulate_scenario(model, scn, config, work / "measurements",
                                                    work / "truth")
    t1 = time.perf_counter()
    try:
        diag = diagnose_blind(csv_path, model, mjcf_path=mjcf_path, seed=scn.index)
    except InputError as exc:  # the diagnosis refused the data: report, do not crash
        diag = {"steps": [], "nominal": {"rms": math.nan}, "final": {"rms": math.nan},
                "unexplained": None, "error": str(exc)}
    diag_s = time.perf_counter() - t1
    write_json(work / "diagnoses" / f"{csv_path.stem}.diagnosis.json", diag, overwrite=True,
               indent=None)
    # only now, after the diagnosis has answered, is the truth read
    truth = json.loads(truth_path.read_text(encoding="utf-8"))
    sc = score(model, truth, diag, config)
    return ScenarioScore(**{**sc.__dict__, "sim_s": sim_s, "diag_s": diag_s})


def _nominal_mjcf(model: Manipulator, path: Path) -> Path:
    """The nominal model's MJCF with its inertias (what the diagnosis may be given)."""
    inertia = "puma560" if model.n == 6 and not model.prismatic.any() else "rods"
    arm = build(model, MJCFOptions(inertia=inertia, visuals=False, floor=False))
    return save_mjcf(arm, path, overwrite=True)


def _run_all(model: Manipulator, scenarios: list[Scenario], config: BenchmarkConfig,
             work: Path, mjcf_path: Path | None, progress: bool, jobs: int
             ) -> list[ScenarioScore]:
    """Every scenario in this process (``jobs`` = 1) or in a pool of worker processes."""
    scores: list[ScenarioScore] = []
    with tqdm(total=len(scenarios), desc="gap-benchmark", unit="scenario",
              disable=not progress) as bar:

        def done(sc: ScenarioScore) -> None:
            scores.append(sc)
            bar.update(1)
            bar.set_postfix(ok=f"{sum(s.success for s in scores)}/{len(scores)}")

        if jobs == 1:
            for scn in scenarios:
                done(_scenario(model, scn, config, work, mjcf_path))
        else:
            with ProcessPoolExecutor(max_workers=jobs,
                                     mp_context=mp.get_context("spawn")) as ex:
                futs = [ex.submit(_scenario, model, scn, config, work, mjcf_path)
                        for scn in scenarios]
                for f in as_completed(futs):
                    done(f.result())
    scores.sort(key=lambda s: s.index)
    return scores


def run_benchmark(model: Manipulator, config: BenchmarkConfig,
                  workdir: str | os.PathLike[str], *, progress: bool = True,
                  jobs: int = 1) -> BenchmarkResult:
    """Draw, simulate, diagnose blind and score ``config.scenarios`` scenarios.

    Files: ``workdir/measurements/*.csv`` (what the diagnosis sees), ``workdir/truth/*.json``
    (what only the scorer reads, after the diagnosis), ``workdir/diagnoses/*.json`` and the
    nominal MJCF ``workdir/nominal.xml``; they are generated and replaced, and the work folder
    is locked for the run (:class:`zrp.output.OutputDir`: a second run into the same folder is
    refused). ``jobs`` > 1 runs scenarios in that many worker processes (results are
    identical: each scenario has its own seed).
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise InputError(f"jobs: expected a positive number of worker processes, got {jobs!r}")
    with OutputDir(workdir, overwrite=True) as out:
        work = out.root
        for d in WORK_FOLDERS:
            (work / d).mkdir(parents=True, exist_ok=True)
        mjcf_path = _nominal_mjcf(model, work / "nominal.xml") if config.use_mjcf else None
        t0 = time.perf_counter()
        scenarios = draw_scenarios(model, config)
        scores = _run_all(model, scenarios, config, work, mjcf_path, progress, jobs)
        wall = time.perf_counter() - t0
    return BenchmarkResult(config, model.name, tuple(scores), wall,
                           sum(s.sim_s for s in scores), sum(s.diag_s for s in scores),
                           str(work))
