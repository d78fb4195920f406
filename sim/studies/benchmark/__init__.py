"""The blind benchmark of the gap diagnosis: physics-made measurements with withheld causes.

For each scenario (:func:`draw_scenarios`): a hidden effect (or none, or two) with a random
magnitude is built into the MuJoCo "real" robot (:mod:`sim.robot.real`), the robot is measured
like a laser-tracker calibration (:mod:`sim.robot.measurement`), and the measurement CSV and a
SEPARATE truth file are written. The diagnosis then runs on the CSV alone
(:func:`diagnose_blind`: it receives the CSV path, the nominal model and the nominal MJCF -
never the scenario, the truth file or anything derived from them). Only afterwards does
:func:`score` open the truth file and judge the diagnosis:

* **excitation**: how much of each hidden effect the poses make visible, i.e. the RMS of its
  own tool-point signature after the best registration (instrument frame and tool offsets) has
  absorbed what it can, over the noise RMS sqrt(3) sigma. Below 1 the effect hides in the
  noise or in the registration (e.g. a joint-1 offset is a turn of the instrument frame), and
  the right answer is ``none``;
* **effect named first** is the right one (or ``none`` when nothing visible was hidden);
* **joints located**: the injected joints (bodies for ``link_length``) are among those the
  diagnosis names for that effect;
* **withheld RMS after correction** over the true noise RMS (target <= 1.5), and the shrink
  ratio final / nominal withheld RMS.

:func:`run_benchmark` does all of it with a progress bar (optionally on any executor, e.g. Dask);
:func:`write_outputs` writes the confusion matrix and summary tables.

The package, by concept: :mod:`.scenarios` (configuration, drawing - the truth),
:mod:`.blind` (simulation and the blind diagnosis), :mod:`.scoring`, :mod:`.results` (the
result and its tables), :mod:`.runner` (the run, on any executor, resumable) and :mod:`.report`
(Markdown, CSV, JSON, the plot).
"""


from sim.studies.benchmark.blind import diagnose_blind, simulate_scenario
from sim.studies.benchmark.report import OUTPUT_FILES, output_names, render_text, write_outputs
from sim.studies.benchmark.results import BenchmarkResult, confusion_matrix, summary_rows
from sim.studies.benchmark.runner import WORK_FOLDERS, run_benchmark
from sim.studies.benchmark.scenarios import (
    KINDS,
    BenchmarkConfig,
    Scenario,
    draw_scenarios,
    typical_gravity_torque,
)
from sim.studies.benchmark.scoring import (
    JOINT_SPACE,
    ScenarioScore,
    effect_signatures,
    registered_rms,
    score,
)

__all__ = [
    "JOINT_SPACE",
    "KINDS",
    "OUTPUT_FILES",
    "WORK_FOLDERS",
    "BenchmarkConfig",
    "BenchmarkResult",
    "Scenario",
    "ScenarioScore",
    "confusion_matrix",
    "diagnose_blind",
    "draw_scenarios",
    "effect_signatures",
    "output_names",
    "registered_rms",
    "render_text",
    "run_benchmark",
    "score",
    "simulate_scenario",
    "summary_rows",
    "typical_gravity_torque",
    "write_outputs",
]
