"""Blind benchmark, motion scenarios: the MuJoCo real robot executes random joint moves with a
hidden motion effect (or none, or two), a tracker streams time-stamped points at 1 kHz, and
``zrp.gap.motion.diagnose_motion`` runs on the trajectory CSV alone (plus the nominal MJCF's
inverse-dynamics torques); only then is the truth file opened and the answer scored like the
static scenarios: the right effect first (or ``none``), the hidden joints among those named,
and the withheld RMS after correction within 1.5x the true noise RMS (sqrt(3) sigma).

Scenarios (:func:`draw_motion_scenarios`, seeded): two without an effect, then the five
effects alone in turn, then the ten pairs in turn. Magnitudes: sync delay 1-5 ms; servo lag
3-10 ms on one of joints 1-3; friction 0.3-1 mrad of play (F = r kp) on one of joints 1-3;
compliance 10-40 urad/(N m) on joint 2 or 3; residual vibration 4-15 Hz, damping ratio
0.02-0.1, on one of joints 1-3 (joint 1 when paired with compliance on the same joint). All
are chosen visible on these moves (a few times the noise or more); the benchmark does not
test the edge of visibility.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from mjcf import MJCFOptions, build
from mjcf.dynamics import inverse_dynamics_torques, mode_terms
from sim.robot.instrument import random_instrument
from sim.robot.motion import MOTION_HIDDEN, MotionEffects, execute_trajectory
from sim.studies.trajectories import named_command
from zrp import jsonio
from zrp.errors import InputError
from zrp.gap.motion import diagnose_motion, load_trajectory, write_trajectory
from zrp.jsonio import dict_from_dataclass
from zrp.model.manipulator import Manipulator
from zrp.output import OutputDir, write_text

__all__ = ["MotionScenario", "MotionScore", "draw_motion_scenarios", "run_motion_benchmark"]

SERVO_KP = 2.0e4  # N m/rad, the real robot's default servo stiffness (friction play = F / kp)


@dataclass(frozen=True)
class MotionScenario:
    """One scenario: an id, its seed and the hidden effects (the truth)."""

    index: int
    seed: int
    effects: MotionEffects


def _one(effect: str, rng: np.random.Generator) -> dict[str, Any]:
    if effect == "sync_delay":
        return {"sync_delay": float(rng.uniform(1e-3, 5e-3))}
    if effect == "servo_lag":
        return {"servo_lag": {int(rng.integers(1, 4)): float(rng.uniform(3e-3, 10e-3))}}
    if effect == "reversal_friction":
        return {"reversal_friction": {int(rng.integers(1, 4)):
                                      float(rng.uniform(3e-4, 1e-3) * SERVO_KP)}}
    if effect == "dynamic_compliance":
        return {"dynamic_compliance": {int(rng.integers(2, 4)): float(rng.uniform(1e-5, 4e-5))}}
    return {"residual_vibration": {int(rng.integers(1, 4)): float(rng.uniform(4.0, 15.0))},
            "vibration_damping": float(rng.uniform(0.02, 0.1))}


def draw_motion_scenarios(count: int, seed: int) -> list[MotionScenario]:
    """``count`` scenarios: 2 without effects, singles for 60 % of the rest, then pairs."""
    if count < 3:
        raise InputError(f"count: expected at least 3 scenarios, got {count}")
    rng = np.random.default_rng(seed)
    pairs = list(itertools.combinations(MOTION_HIDDEN, 2))
    n_single = round(0.6 * (count - 2))
    out = []
    for i in range(count):
        kw: dict[str, Any] = {}
        if i >= 2 and i - 2 < n_single:
            kw = _one(MOTION_HIDDEN[(i - 2) % len(MOTION_HIDDEN)], rng)
        elif i >= 2:
            for e in pairs[(i - 2 - n_single) % len(pairs)]:
                kw.update(_one(e, rng))
            vib, comp = kw.get("residual_vibration", {}), kw.get("dynamic_compliance", {})
            if set(vib) & set(comp):  # one joint cannot be both: the mode moves to joint 1
                kw["residual_vibration"] = {1: vib[next(iter(vib))]}
        out.append(MotionScenario(i, int(rng.integers(2**31)), MotionEffects(**kw)))
    return out


@dataclass(frozen=True)
class MotionScore:
    """The score of one scenario (see the module doc)."""

    index: int
    hidden: tuple[str, ...]
    hidden_joints: dict[str, tuple[int, ...]]
    found: tuple[str, ...]
    found_joints: tuple[tuple[int, ...], ...]
    top_correct: bool
    joints_correct: bool
    all_found: bool
    ratio: float
    noise_sigma: float
    sim_s: float
    diagnose_s: float

    @property
    def success(self) -> bool:
        return self.top_correct and self.joints_correct and self.ratio <= 1.5

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self), "success": self.success}


def _score(scn: MotionScenario, diag: Any, truth: dict[str, Any], sim_s: float,
           diag_s: float) -> MotionScore:
    eff = scn.effects
    hidden = eff.active
    found = tuple(s.effect for s in diag.steps)
    fj = tuple(tuple(s.joints) for s in diag.steps)
    top_ok = (found[:1] == ("none",) or not found) if not hidden else \
        bool(found) and found[0] in hidden
    joints_ok = True
    for e in hidden:
        if e in found:
            named = set(fj[found.index(e)])
            joints_ok &= e == "sync_delay" or set(eff.joints(e)) <= named
        elif found and e == found[0]:
            joints_ok = False
    if hidden and (not found or found[0] not in hidden):
        joints_ok = False
    ratio = diag.final.rms / (math.sqrt(3.0) * truth["noise_sigma"])
    return MotionScore(scn.index, hidden, {e: eff.joints(e) for e in hidden}, found, fj,
                       bool(top_ok), bool(joints_ok), set(hidden) <= set(found), float(ratio),
                       float(truth["noise_sigma"]), sim_s, diag_s)


def _run_one(model: Manipulator, scn: MotionScenario, work: Path, arm_model: Any,
             moves: int) -> MotionScore:
    rng = np.random.default_rng(scn.seed)
    command, duration = named_command(model, "moves", rng, moves)
    inst = random_instrument(model, rng)  # 0.01-0.03 mm in the model's unit
    t0 = time.perf_counter()
    run = execute_trajectory(model, command, duration, scn.effects, inst, rng)
    csv_path = work / "measurements" / f"motion_{scn.index:03d}.csv"
    truth_path = work / "truth" / f"motion_{scn.index:03d}.truth.json"
    write_trajectory(run.trajectory, csv_path, overwrite=True)
    write_text(truth_path, jsonio.dumps(run.truth), overwrite=True)
    sim_s = time.perf_counter() - t0
    # blind: the diagnosis sees the CSV, the nominal model and the nominal MJCF only
    t1 = time.perf_counter()
    traj = load_trajectory(csv_path, model)
    tau = inverse_dynamics_torques(arm_model, traj.q, traj.qd, traj.qdd)
    terms = mode_terms(arm_model, traj.q, traj.qd, traj.qdd)
    # the thorough setting: a denser search and every fitting sample in the final fit
    diag = diagnose_motion(model, traj, torque=tau, mode_terms=terms, seed=scn.seed % 1000,
                           max_search_samples=4000, max_fit_samples=10**9)
    diag_s = time.perf_counter() - t1
    truth = _load_truth(truth_path)
    return _score(scn, diag, truth, sim_s, diag_s)


def _load_truth(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text())


def run_motion_benchmark(model: Manipulator, count: int, seed: int, out: str | Path, *,
                         moves: int = 10, overwrite: bool = False, progress: bool = False
                         ) -> dict[str, Any]:
    """Run ``count`` motion scenarios; write ``summary.json`` and ``summary.md`` into ``out``
    (work files under ``out/work``). Returns the summary."""
    scenarios = draw_motion_scenarios(count, seed)
    arm = build(model, MJCFOptions(inertia="puma560" if model.n == 6 else "rods"))
    with OutputDir(out, overwrite=overwrite) as od:
        work = Path(out) / "work"
        scores = [_run_one(model, s, work, arm.model, moves)
                  for s in tqdm(scenarios, disable=not progress, desc="motion scenarios")]
        summary = summarise(scores)
        od.write_json("summary.json", summary)
        od.write_text("summary.md", markdown(summary))
    return summary


def _rate(sel: list[MotionScore], attr: str) -> list[int]:
    """[how many of ``sel`` have ``attr`` true, how many there are]."""
    return [sum(bool(getattr(s, attr)) for s in sel), len(sel)]


def _ratio_ok(sel: list[MotionScore]) -> list[int]:
    """[how many of ``sel`` end within 1.5x the noise, how many there are]."""
    return [sum(s.ratio <= 1.5 for s in sel), len(sel)]


def _kind_row(sel: list[MotionScore]) -> dict[str, list[int]]:
    return {"top_correct": _rate(sel, "top_correct"),
            "joints_correct": _rate(sel, "joints_correct"), "ratio_ok": _ratio_ok(sel),
            "all_found": _rate(sel, "all_found"), "success": _rate(sel, "success")}


def summarise(scores: list[MotionScore]) -> dict[str, Any]:
    """Counts and rates over all scenarios, per kind (none / single / pair)."""
    kinds = {"none": [s for s in scores if not s.hidden],
             "single": [s for s in scores if len(s.hidden) == 1],
             "pair": [s for s in scores if len(s.hidden) == 2]}
    right = [s.top_correct and s.joints_correct for s in scores]
    return {"scenarios": len(scores), "by_kind": {k: _kind_row(v) for k, v in kinds.items()},
            "right_effect_and_joints": [sum(right), len(scores)],
            "ratio_ok": _ratio_ok(scores),
            "median_ratio": float(np.median([s.ratio for s in scores])),
            "diagnose_s_median": float(np.median([s.diagnose_s for s in scores])),
            "sim_s_median": float(np.median([s.sim_s for s in scores])),
            "scores": [s.to_dict() for s in scores]}


def markdown(summary: dict[str, Any]) -> str:
    """The summary as a Markdown table and one line per scenario."""
    r, n = summary["right_effect_and_joints"]
    o, _ = summary["ratio_ok"]
    lines = ["# Motion benchmark", "",
             f"{summary['scenarios']} scenarios: right effect and joints {r}/{n}, withheld RMS "
             f"<= 1.5x noise {o}/{n} (median ratio {summary['median_ratio']:.2f}).", "",
             "| kind | right effect | joints | RMS target | both found | success |",
             "|---|---|---|---|---|---|"]
    for k, v in summary["by_kind"].items():
        cells = " | ".join(f"{a}/{b}" for a, b in (v["top_correct"], v["joints_correct"],
                                                    v["ratio_ok"], v["all_found"], v["success"]))
        lines.append(f"| {k} | {cells} |")
    lines += ["", "| # | hidden | found | ratio | ok |", "|---|---|---|---|---|"]
    for s in summary["scores"]:
        hid = ", ".join(f"{e}{list(j)}" for e, j in s["hidden_joints"].items()) or "none"
        fnd = ", ".join(f"{e}{list(j)}" for e, j in zip(s["found"], s["found_joints"],
                                                         strict=True)) or "none"
        lines.append(f"| {s['index']} | {hid} | {fnd} | {s['ratio']:.2f} | "
                     f"{'yes' if s['success'] else 'no'} |")
    return "\n".join(lines) + "\n"
