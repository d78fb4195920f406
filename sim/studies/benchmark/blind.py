"""Blind benchmark, part 2: simulate and measure a scenario, then diagnose the CSV blind.

:func:`simulate_scenario` sees the truth: it builds the real robot of a scenario, measures it
and writes the measurement CSV and a SEPARATE truth file. :func:`diagnose_blind` is the only
place the benchmark calls the diagnosis; it receives the CSV path, the nominal model and the
nominal MJCF (or the arm's own URDF/MJCF) - never the scenario, the truth file or anything
derived from them.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from mjcf.gravity import gravity_torques
from sim.robot.instrument import random_instrument
from sim.robot.mass import DynamicsFallbackWarning
from sim.robot.measurement import Procedure, measure, write_measurements, write_truth
from sim.robot.real import RealRobot
from sim.studies.benchmark.scenarios import BenchmarkConfig, Scenario, pose_limits
from sim.studies.trajectories import circle_poses
from zrp.gap import Diagnosis, diagnose, load_measurements
from zrp.gap.report import diagnosis_document
from zrp.kinematics import reachable_poses
from zrp.model.manipulator import Manipulator

__all__ = ["diagnose_blind", "diagnose_blind_result", "simulate_scenario"]


def simulate_scenario(model: Manipulator, scenario: Scenario, config: BenchmarkConfig,
                      measurement_dir: Path, truth_dir: Path) -> tuple[Path, Path, float]:
    """Simulate and measure one scenario; write ``measurement_dir/scenario_XXX.csv`` and
    ``truth_dir/scenario_XXX.truth.json``. Returns both paths and the wall time (s)."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(scenario.seed)
    q = (reachable_poses(model, config.poses, rng, limits=pose_limits(model))
         if config.poses_from == "random"
         else circle_poses(model, config.poses))
    inst = random_instrument(model, rng, scenario.noise_sigma)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsFallbackWarning)  # the run's report says it
        robot = RealRobot(model, scenario.effects, config.robot_options(model))
        run = measure(robot, q, inst, rng, Procedure(approach=config.approach))
    run.truth["scenario"] = {"index": scenario.index, "seed": scenario.seed,
                             "kind": scenario.kind, "labels": list(scenario.labels)}
    name = f"scenario_{scenario.index:03d}"
    csv_path = write_measurements(run, measurement_dir / f"{name}.csv", overwrite=True)
    truth_path = write_truth(run, truth_dir / f"{name}.truth.json", overwrite=True)
    return csv_path, truth_path, time.perf_counter() - t0


def diagnose_blind(csv_path: str | Path, model: Manipulator, *, mjcf_path: str | Path | None,
                   seed: int = 0) -> dict[str, Any]:
    """Run the diagnosis on a measurement CSV exactly as a user would, and return its JSON.

    This is the only place the benchmark calls the diagnosis. It receives the CSV path, the
    nominal model and the nominal MJCF - nothing about the scenario. Warnings of the diagnosis
    are kept in the returned document, not printed.
    """
    return diagnosis_document(diagnose_blind_result(csv_path, model, mjcf_path=mjcf_path,
                                                    seed=seed))


def diagnose_blind_result(csv_path: str | Path, model: Manipulator, *,
                          mjcf_path: str | Path | None, seed: int = 0,
                          residual_model: bool = False) -> Diagnosis:
    """:func:`diagnose_blind`, returning the :class:`zrp.gap.Diagnosis` itself (the
    compensated column takes the calibrated robot out of it); ``residual_model``: also train
    the learned residual term (the remainder scenarios, :mod:`.remainder`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meas = load_measurements(csv_path, model)
        tau = None if mjcf_path is None else gravity_torques(
            mjcf_path, meas.q_pose, joint_names=[j.name for j in model.joints])
        return diagnose(model, meas, gravity_torque=tau, seed=seed,
                        residual_model=residual_model)
