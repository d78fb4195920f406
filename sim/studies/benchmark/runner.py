"""Blind benchmark, part 5: the run - draw, simulate, diagnose blind, score - in this process
or on any ``concurrent.futures``-style executor (a Dask cluster from the command line's
``--workers`` / ``--scheduler``; results are identical: each scenario has its own seed).

Each scenario's score is written to ``workdir/scores/scenario_XXX.score.json`` as soon as it
arrives, so an interrupted run resumes (``resume=True``) with the scenarios it had not
finished. A scenario whose simulation or scoring raises is reported with its index, seed and
effects (:class:`zrp.tasks.TaskFailure`); the others still run.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import Executor
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from tqdm.auto import tqdm

from mjcf import MJCFOptions, build, save_mjcf
from sim.studies.benchmark.blind import diagnose_blind_result, simulate_scenario
from sim.studies.benchmark.compensated import compensated_column
from sim.studies.benchmark.results import BenchmarkResult
from sim.studies.benchmark.scenarios import BenchmarkConfig, Scenario, draw_scenarios
from sim.studies.benchmark.scoring import ScenarioScore, score
from zrp.errors import InputError
from zrp.gap.report import diagnosis_document
from zrp.gap.results import load_diagnosis
from zrp.jsonio import dumps
from zrp.model.manipulator import Manipulator
from zrp.output import OutputDir, write_json
from zrp.tasks import TaskFailure, map_tasks

__all__ = ["WORK_FOLDERS", "ScenarioTask", "run_benchmark", "run_scenario", "score_from_dict"]

#: Sub-folders of the work folder: what the diagnosis sees, what only the scorer reads, the
#: diagnoses and the scores (written as they arrive; read back on resume).
WORK_FOLDERS = ("measurements", "truth", "diagnoses", "scores")


@dataclass(frozen=True)
class ScenarioTask:
    """One scenario's work, picklable for a worker process or machine."""

    model: Manipulator
    scenario: Scenario
    config: BenchmarkConfig
    work: Path
    mjcf_path: Path | None

    def __str__(self) -> str:
        s = self.scenario
        return (f"scenario {s.index} (seed {s.seed}, {s.kind}: "
                f"{', '.join(s.labels) or 'none'})")


def run_scenario(task: ScenarioTask) -> ScenarioScore:
    """Simulate, diagnose blind, then score one scenario (in this process or a worker)."""
    model, scn, config, work = task.model, task.scenario, task.config, task.work
    csv_path, truth_path, sim_s = simulate_scenario(model, scn, config, work / "measurements",
                                                    work / "truth")
    t1 = time.perf_counter()
    result = None
    try:
        result = diagnose_blind_result(csv_path, model, mjcf_path=task.mjcf_path,
                                       seed=scn.index)
        doc = diagnosis_document(result)
    except InputError as exc:  # the diagnosis refused the data: report, do not crash
        doc = {"steps": [], "nominal": {"rms": math.nan}, "final": {"rms": math.nan},
               "unexplained": None, "error": str(exc)}
    diag_s = time.perf_counter() - t1
    write_json(work / "diagnoses" / f"{csv_path.stem}.diagnosis.json", doc, overwrite=True,
               indent=None)
    # only now, after the diagnosis has answered, is the truth read
    truth = json.loads(truth_path.read_text(encoding="utf-8"))
    sc = score(model, truth, load_diagnosis(doc), config)
    values = dict(sc.values)
    if config.compensate and result is not None:
        values.update(compensated_column(model, scn, truth, result, task.mjcf_path,
                                         config.compensate, config.robot_options(model)))
    return ScenarioScore(**{**sc.__dict__, "sim_s": sim_s, "diag_s": diag_s,
                            "values": values})


def _nan_if_none(v: Any) -> float:
    return math.nan if v is None else float(v)


#: how each field of :class:`ScenarioScore` comes back from its JSON (the others as they are).
_FROM_JSON: dict[str, Any] = {
    **dict.fromkeys(("hidden", "expected", "found", "tied"), tuple),
    **dict.fromkeys(("noise_rms", "nominal_rms", "final_rms", "ratio", "shrink", "sim_s",
                     "diag_s", "payload"), _nan_if_none),
    "found_joints": lambda v: tuple(tuple(j) for j in v),
    "hidden_joints": lambda v: {e: tuple(j) for e, j in v.items()},
    "snr": lambda v: {e: _nan_if_none(x) for e, x in v.items()},
}


def score_from_dict(d: dict[str, Any]) -> ScenarioScore:
    """The inverse of :meth:`ScenarioScore.to_dict` (JSON nulls back to NaN)."""
    names = {f.name for f in fields(ScenarioScore)} - {"values"}
    kw = {k: _FROM_JSON.get(k, lambda v: v)(d[k]) for k in names}
    values = {k: v for k, v in d.items() if k not in names and k != "excited"}
    return ScenarioScore(**kw, values=values)


def _score_path(work: Path, index: int) -> Path:
    return work / "scores" / f"scenario_{index:03d}.score.json"


def _nominal_mjcf(model: Manipulator, path: Path) -> Path:
    """The nominal model's MJCF with its inertias (what the diagnosis may be given)."""
    inertia = "puma560" if model.n == 6 and not model.prismatic.any() else "rods"
    arm = build(model, MJCFOptions(inertia=inertia, visuals=False, floor=False))
    return save_mjcf(arm, path, overwrite=True)


def _config_dict(model: Manipulator, config: BenchmarkConfig) -> dict[str, Any]:
    return {"model": model.name, **{k: (list(v) if isinstance(v, tuple) else v)
                                    for k, v in config.__dict__.items()}}


def _previous(work: Path, scenarios: list[Scenario], config: dict[str, Any]
              ) -> dict[int, ScenarioScore]:
    """Scores a previous (interrupted) run of the same configuration wrote."""
    cfg_path = work / "scores" / "config.json"
    if cfg_path.exists() and json.loads(cfg_path.read_text(encoding="utf-8")) != \
            json.loads(dumps(config)):
        raise InputError(f"resume: {cfg_path} holds another configuration; run without "
                         "resume (or into another work folder)")
    done = {}
    for scn in scenarios:
        path = _score_path(work, scn.index)
        if path.exists():
            sc = score_from_dict(json.loads(path.read_text(encoding="utf-8")))
            if sc.kind == scn.kind and sc.hidden == scn.labels:
                done[scn.index] = sc
    return done


def _run_all(tasks: list[ScenarioTask], done: dict[int, ScenarioScore], progress: bool,
             executor: Executor | Any | None) -> tuple[list[ScenarioScore], list[TaskFailure]]:
    """Every scenario not yet ``done``, in this process or on the executor."""
    scores = list(done.values())
    failures: list[TaskFailure] = []
    todo = [t for t in tasks if t.scenario.index not in done]
    with tqdm(total=len(tasks), initial=len(done), desc="gap-benchmark", unit="scenario",
              disable=not progress) as bar:
        for _, res in map_tasks(run_scenario, todo, executor, capture=True, describe=str):
            if isinstance(res, TaskFailure):
                failures.append(res)
            else:
                write_json(_score_path(tasks[0].work, res.index), res.to_dict(),
                           overwrite=True, indent=None)
                scores.append(res)
            bar.update(1)
            bar.set_postfix(ok=f"{sum(s.success for s in scores)}/{len(scores)}",
                            failed=len(failures))
    scores.sort(key=lambda s: s.index)
    return scores, failures


def run_benchmark(model: Manipulator, config: BenchmarkConfig,
                  workdir: str | os.PathLike[str], *, progress: bool = True,
                  executor: Executor | Any | None = None,
                  resume: bool = False) -> BenchmarkResult:
    """Draw, simulate, diagnose blind and score ``config.scenarios`` scenarios.

    Files: ``workdir/measurements/*.csv`` (what the diagnosis sees), ``workdir/truth/*.json``
    (what only the scorer reads, after the diagnosis), ``workdir/diagnoses/*.json``,
    ``workdir/scores/*.json`` (each written as it arrives) and the nominal MJCF
    ``workdir/nominal.xml``; they are generated and replaced, and the work folder is locked
    for the run (:class:`zrp.output.OutputDir`: a second run into the same folder is refused).

    Args:
        executor: None (this process) or any ``concurrent.futures``-style executor (a Dask
            ``Client.get_executor()``; the workers must see ``workdir``). Results are
            identical: each scenario has its own seed.
        resume: keep the scores a previous run of the same configuration wrote into
            ``workdir/scores`` and run only the other scenarios.
    """
    with OutputDir(workdir, overwrite=True) as out:
        work = out.root
        for d in WORK_FOLDERS:
            (work / d).mkdir(parents=True, exist_ok=True)
        if not resume:
            for old in (work / "scores").glob("*.json"):
                old.unlink()
        cfg = _config_dict(model, config)
        config.robot_options(model)  # the arm file read and matched to the model now
        mjcf_path = (None if not config.use_mjcf else Path(config.arm_file)
                     if config.arm_file is not None else
                     _nominal_mjcf(model, work / "nominal.xml"))
        t0 = time.perf_counter()
        scenarios = draw_scenarios(model, config)
        done = _previous(work, scenarios, cfg) if resume else {}
        write_json(work / "scores" / "config.json", cfg, overwrite=True)
        tasks = [ScenarioTask(model, scn, config, work, mjcf_path) for scn in scenarios]
        scores, failures = _run_all(tasks, done, progress, executor)
        wall = time.perf_counter() - t0
    return BenchmarkResult(config, model.name, tuple(scores), wall,
                           sum(s.sim_s for s in scores), sum(s.diag_s for s in scores),
                           str(work), tuple(failures), len(done),
                           config.dynamics_note(model))
