"""Blind benchmark, part 6: what remains - effects the library lacks, and none (issue 36).

The other parts draw effects the diagnosis has; these scenarios hide what it has not, or
nothing, and judge the test of what remains (:mod:`zrp.gap.analysis.structure`) and the
learned residual term (:mod:`zrp.gap.analysis.residual`):

* **lacking** - a gear error at a harmonic the library's cyclic error lacks (it has 1 and 2):
  the 3rd harmonic of joint 2, then the 4th of joints 2 and 3. The diagnosis must say that a
  structured remainder exists and name the effect's joints, and the learned term must be kept
  with a withheld RMS within :data:`WITHIN_NOISE` x the tracker's pure-noise RMS
  (sqrt(3) sigma). Also reported: the share of the structured remainder the term recovers
  on the withheld poses, ``1 - (hybrid^2 - noise^2) / (physical^2 - noise^2)`` (mean squares
  above the pure noise's);
* **effect-free** - no hidden effect; **scatter only** - no hidden effect, and every pose's
  reflectors shifted together by a draw of N(0, s^2) per coordinate, which no joint angle
  predicts (a tracker that wanders between readings). Both must give "no structure" and no
  learned term kept.

Each scenario is simulated on the MuJoCo robot and measured (:func:`simulate_remainder`,
which alone sees the truth and writes it to a separate file); the CSV is diagnosed blind by
:func:`~sim.studies.benchmark.blind.diagnose_blind_result` (the CSV path and the nominal model,
nothing else) with the learned term asked for; only then is the truth read and the answer
scored (:func:`score_remainder`). The magnitudes are fixed below, not drawn.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sim.robot.effects import HiddenEffects
from sim.robot.instrument import random_instrument
from sim.robot.mass import DynamicsFallbackWarning
from sim.robot.measurement import Procedure, measure, write_measurements, write_truth
from sim.robot.real import RealRobot
from sim.studies.benchmark.blind import diagnose_blind_result
from sim.studies.benchmark.scenarios import pose_limits
from zrp.gap.report import diagnosis_document
from zrp.kinematics import reachable_poses
from zrp.model.manipulator import Manipulator
from zrp.output import write_json

__all__ = ["REMAINDER_SCENARIOS", "WITHIN_NOISE", "RemainderScenario", "RemainderScore",
           "remainder_table", "run_remainder_benchmark", "score_remainder",
           "simulate_remainder"]

#: the learned term's withheld RMS must be within this multiple of the pure-noise RMS.
WITHIN_NOISE = 1.2


@dataclass(frozen=True)
class RemainderScenario:
    """One scenario (the truth: it never reaches the diagnosis).

    Attributes:
        name: a short label; kind: "lacking", "effect-free" or "scatter".
        effects: the hidden effects; joints: the joints the lacking effect depends on.
        scatter: per-pose shift of all reflectors, sigma per coordinate (length unit).
        noise_sigma: tracker noise per coordinate (length unit); seed: its generator's seed.
    """

    name: str
    kind: str
    effects: HiddenEffects
    joints: tuple[int, ...] = ()
    scatter: float = 0.0
    noise_sigma: float = 0.02
    seed: int = 0


#: the scenarios (PUMA 560 in mm: 0.3 mrad at joint 2 is about 0.2 mm at the tool).
REMAINDER_SCENARIOS = (
    RemainderScenario("harmonic 3 on joint 2", "lacking",
                      HiddenEffects(cyclic_error={2: (3, 0.3e-3, 0.1e-3)}), (2,), seed=101),
    RemainderScenario("harmonic 4 on joints 2 and 3", "lacking",
                      HiddenEffects(cyclic_error={2: (4, 0.2e-3, 0.0), 3: (4, 0.0, 0.25e-3)}),
                      (2, 3), seed=102),
    RemainderScenario("effect-free", "effect-free", HiddenEffects(), seed=103),
    RemainderScenario("scatter only", "scatter", HiddenEffects(), scatter=0.05, seed=104),
)


@dataclass(frozen=True)
class RemainderScore:
    """What the blind diagnosis said of one scenario, judged against its truth."""

    name: str
    kind: str
    structured: bool
    share: float
    interval: tuple[float, float]
    named: tuple[str, ...]
    kept: bool
    withheld_physical: float
    withheld_hybrid: float
    noise_rms: float
    recovered: float
    passed: bool
    why: str
    sim_s: float
    diag_s: float


def simulate_remainder(model: Manipulator, scn: RemainderScenario, poses: int,
                       measurement_dir: Path, truth_dir: Path) -> tuple[Path, Path]:
    """Simulate and measure ``scn``; write the CSV and, separately, the truth."""
    rng = np.random.default_rng(scn.seed)
    q = reachable_poses(model, poses, rng, limits=pose_limits(model))
    inst = random_instrument(model, rng, scn.noise_sigma)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsFallbackWarning)
        run = measure(RealRobot(model, scn.effects), q, inst, rng, Procedure())
    if scn.scatter:
        m = run.measurements
        _, inv = np.unique(m.pose, return_inverse=True)
        shift = rng.normal(scale=scn.scatter, size=(inv.max() + 1, 3))[inv]
        run = dataclasses.replace(run, measurements=dataclasses.replace(m, xyz=m.xyz + shift))
    run.truth["remainder_scenario"] = {"name": scn.name, "kind": scn.kind,
                                       "joints": list(scn.joints), "scatter": scn.scatter}
    stem = "remainder_" + "".join(c if c.isalnum() else "_" for c in scn.name)
    return (write_measurements(run, measurement_dir / f"{stem}.csv", overwrite=True),
            write_truth(run, truth_dir / f"{stem}.truth.json", overwrite=True))


def score_remainder(doc: dict[str, Any], truth: dict[str, Any]) -> dict[str, Any]:
    """Judge a blind diagnosis document against the truth file (module docstring)."""
    s = (doc.get("remainder") or {}).get("structure") or {}
    rm = doc.get("residual_model") or {}
    noise = math.sqrt(3) * float(truth["instrument"]["noise_sigma"])
    sc = truth["remainder_scenario"]
    structured, kept = bool(s.get("structured")), bool(rm.get("kept"))
    named = tuple(s.get("named") or ())
    hybrid = float(rm.get("withheld_rms_hybrid", math.nan))
    phys = float(rm.get("withheld_rms_physical", math.nan))
    above = phys**2 - noise**2
    recovered = 1.0 - (hybrid**2 - noise**2) / above if above > 0 else math.nan
    if sc["kind"] == "lacking":
        want = {f"q{j}" for j in sc["joints"]}
        checks = [(structured, "no structure found"),
                  (want <= set(named), f"joints {sorted(want)} not all named"),
                  (kept, "learned term not kept"),
                  (hybrid <= WITHIN_NOISE * noise,
                   f"learned term {hybrid / noise:.2f}x the noise")]
    else:
        checks = [(not structured, "structure claimed"), (not kept, "learned term kept")]
    why = "; ".join(w for ok, w in checks if not ok)
    return {"structured": structured, "share": float(s.get("share", math.nan)),
            "interval": tuple(s.get("interval") or (math.nan, math.nan)), "named": named,
            "kept": kept, "withheld_physical": phys, "withheld_hybrid": hybrid,
            "noise_rms": noise, "recovered": recovered, "passed": not why, "why": why}


def run_remainder_benchmark(model: Manipulator, work: Path, *, poses: int = 800,
                            scenarios: tuple[RemainderScenario, ...] = REMAINDER_SCENARIOS
                            ) -> list[RemainderScore]:
    """Simulate, diagnose blind (with the learned term), then score every scenario."""
    out = []
    for i, scn in enumerate(scenarios):
        t0 = time.perf_counter()
        csv_path, truth_path = simulate_remainder(model, scn, poses, work / "measurements",
                                                  work / "truth")
        t1 = time.perf_counter()
        doc = diagnosis_document(diagnose_blind_result(csv_path, model, mjcf_path=None,
                                                       seed=i, residual_model=True))
        t2 = time.perf_counter()
        write_json(work / "diagnoses" / f"{csv_path.stem}.diagnosis.json", doc,
                   overwrite=True, indent=None)
        truth = json.loads(truth_path.read_text(encoding="utf-8"))  # only now
        out.append(RemainderScore(scn.name, scn.kind, **score_remainder(doc, truth),
                                  sim_s=t1 - t0, diag_s=t2 - t1))
    return out


def remainder_table(scores: list[RemainderScore], unit: str) -> tuple[list[str], list[tuple]]:
    """(header, rows) of the scores' table."""
    head = ["scenario", "structure (share, 95 %)", "joints named", "learned term",
            f"withheld RMS physical -> learned ({unit})", "x noise", "structure recovered",
            "verdict"]
    rows = []
    for s in scores:
        lo, hi = s.interval
        rows.append((s.name, f"{'yes' if s.structured else 'no'} ({s.share:.2f}, "
                             f"{lo:.2f}-{hi:.2f})", ", ".join(s.named) or "-",
                     "kept" if s.kept else "not kept",
                     f"{s.withheld_physical:.4g} -> {s.withheld_hybrid:.4g}",
                     f"{s.withheld_hybrid / s.noise_rms:.2f}",
                     "-" if s.kind != "lacking" else f"{100 * s.recovered:.0f} %",
                     "pass" if s.passed else f"FAIL: {s.why}"))
    return head, rows
